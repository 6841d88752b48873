// The `flowfusion` executable on bad input: exit status 2 and a message naming the culprit,
// with nothing overwritten. Needs the flowfusion_app target built.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "flowfusion/slam/map_file.h"
#include "testing/test_util.h"

namespace fs = std::filesystem;

namespace ff {
namespace {

std::string shellArg(const fs::path& p) { return "'" + p.string() + "'"; }

// The command was refused: exit status 2, a message holding `names`, and `out` not written.
void expectRefused(const testing::CommandResult& r, const std::string& names, const fs::path& out) {
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find(names), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));
}

TEST(CliErrors, RunOnMissingFolder) {
  testing::TempDir tmp;
  const fs::path missing = tmp.path() / "no_such_sequence";
  const auto r = testing::runFlowfusion("run " + shellArg(missing) + " --out " + shellArg(tmp.path() / "out"));
  expectRefused(r, missing.string(), tmp.path() / "out");
}

TEST(CliErrors, RunIntoNonEmptyOutWithoutOverwrite) {
  testing::TempDir tmp;
  const std::string seq = testing::makeTinySequence(tmp.path() / "seq").string();
  const fs::path out = tmp.path() / "out";
  fs::create_directories(out);
  std::ofstream(out / "trajectory.txt") << "precious\n";
  const auto r = testing::runFlowfusion("run " + shellArg(seq) + " --out " + shellArg(out) + " --quiet");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find(out.string()), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("--overwrite"), std::string::npos) << r.output;
  std::ifstream in(out / "trajectory.txt");
  std::string content;
  std::getline(in, content);
  EXPECT_EQ(content, "precious");
  EXPECT_EQ(std::distance(fs::directory_iterator(out), fs::directory_iterator{}), 1);
}

TEST(CliErrors, BadSettingValue) {
  testing::TempDir tmp;
  const std::string seq = testing::makeTinySequence(tmp.path() / "seq").string();
  const auto r = testing::runFlowfusion("run " + shellArg(seq) + " --out " + shellArg(tmp.path() / "out") +
                                        " --set odometry.levels=0");
  expectRefused(r, "odometry.levels", tmp.path() / "out");
}

// A mode of the generators named by --set is one of its names, not silently the first one.
TEST(CliErrors, UnknownModeName) {
  testing::TempDir tmp;
  const auto synth =
      testing::runFlowfusion("synth " + shellArg(tmp.path() / "synth") + " --frames 2 --set camera_motion=spin");
  expectRefused(synth, "camera_motion must be handheld or rpy", tmp.path() / "synth");
  const std::string seq = testing::makeTinySequence(tmp.path() / "seq").string();
  const auto augment = testing::runFlowfusion("augment " + shellArg(seq) + " " + shellArg(tmp.path() / "aug") +
                                              " --set holes=open");
  expectRefused(augment, "holes must be enclosed or black_surfaces", tmp.path() / "aug");
}

TEST(CliErrors, UnknownSetting) {
  testing::TempDir tmp;
  const std::string seq = testing::makeTinySequence(tmp.path() / "seq").string();
  const auto r = testing::runFlowfusion("run " + shellArg(seq) + " --out " + shellArg(tmp.path() / "out") +
                                        " --set nosuch.key=1");
  expectRefused(r, "nosuch", tmp.path() / "out");
}

TEST(CliErrors, NoIntrinsics) {
  testing::TempDir tmp;
  const std::string seq = testing::makeTinySequence(tmp.path() / "plain");
  fs::remove(fs::path(seq) / "camera.txt");
  const auto r = testing::runFlowfusion("run " + shellArg(seq) + " --out " + shellArg(tmp.path() / "out"));
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("--camera"), std::string::npos) << r.output;
}

TEST(CliErrors, NonFiniteOrAbsurdDepthScaleIsRefusedByName) {
  testing::TempDir tmp;
  const std::string seq = testing::makeTinySequence(tmp.path() / "seq").string();
  for (const std::string scale : {"inf", "nan", "1e-30", "0", "-5000", "1e9"}) {
    const auto r = testing::runFlowfusion("run " + shellArg(seq) + " --out " + shellArg(tmp.path() / "out") +
                                          " --depth-scale " + scale);
    EXPECT_EQ(r.status, 2) << scale << ": " << r.output;
    EXPECT_NE(r.output.find("--depth-scale"), std::string::npos) << scale << ": " << r.output;
    EXPECT_FALSE(fs::exists(tmp.path() / "out")) << scale;
  }
  EXPECT_EQ(testing::runFlowfusion("run " + shellArg(seq) + " --out " + shellArg(tmp.path() / "out") +
                                   " --quiet --no-map --depth-scale 1000")
                .status,
            0);
}

// `report` on a folder whose summary.json is not an object, and with a bad --max-points.
TEST(CliErrors, ReportOnAMalformedSummaryOrBadMaxPoints) {
  testing::TempDir tmp;
  const std::string seq = testing::makeTinySequence(tmp.path() / "seq").string();
  const fs::path out = tmp.path() / "out";
  ASSERT_EQ(testing::runFlowfusion("run " + shellArg(seq) + " --out " + shellArg(out) + " --quiet --no-map").status, 0);
  const auto bad_points = testing::runFlowfusion("report " + shellArg(out) + " --max-points -1");
  EXPECT_NE(bad_points.status, 0) << bad_points.output;
  EXPECT_NE(bad_points.output.find("--max-points"), std::string::npos) << bad_points.output;
  EXPECT_FALSE(fs::exists(out / "report.html"));
  std::ofstream(out / "summary.json") << "[1, 2, 3]\n";
  const auto array = testing::runFlowfusion("report " + shellArg(out));
  EXPECT_EQ(array.status, 2) << array.output;
  EXPECT_NE(array.output.find("summary.json: expected a JSON object"), std::string::npos) << array.output;
  EXPECT_EQ(array.output.find("internal error"), std::string::npos) << array.output;
}

// A map file of `camera` with one blank keyframe at the default keyframe images' sizes.
void writeMapOf(const CameraIntrinsics& camera, const fs::path& path) {
  SavedMap map;
  map.camera = camera;
  auto k = std::make_shared<KeyframeImages>();
  k->camera = camera.atLevel(map.keyframe_level);
  const cv::Size size(k->camera.width, k->camera.height);
  const cv::Size small(map.fern_image_width, map.fern_image_width * camera.height / camera.width);
  k->intensity = cv::Mat(size, CV_8U, cv::Scalar(0));
  k->depth = cv::Mat(size, CV_16U, cv::Scalar(0));
  k->static_weight = cv::Mat(size, CV_8U, cv::Scalar(255));
  k->small_bgr = cv::Mat(small, CV_8UC3, cv::Scalar(0, 0, 0));
  k->small_depth = cv::Mat(small, CV_32F, cv::Scalar(0));
  map.keyframes.push_back({SE3::Identity(), k});
  writeMapFile(path.string(), map);
}

TEST(CliErrors, RunRefusesABadMapInByNameWritingNothing) {
  testing::TempDir tmp;
  const std::string seq = testing::makeTinySequence(tmp.path() / "seq").string();
  const fs::path out = tmp.path() / "out";
  const auto refused = [&](const fs::path& map_in, const std::string& reason) {
    const auto r = testing::runFlowfusion("run " + shellArg(seq) + " --out " + shellArg(out) + " --map-in " +
                                          shellArg(map_in) + " --quiet");
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find(map_in.string()), std::string::npos) << "names the map: " << r.output;
    EXPECT_NE(r.output.find(reason), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(out)) << "wrote " << out << " for " << map_in;
  };
  refused(tmp.path() / "no_run", "no map file there");
  std::ofstream(tmp.path() / "junk.ffmap") << "not a map\n";
  refused(tmp.path() / "junk.ffmap", "not a flowfusion map file");
  writeMapOf({100, 100, 63.5, 47.5, 128, 96}, tmp.path() / "other_camera.ffmap");
  refused(tmp.path() / "other_camera.ffmap", "the map is of another camera: 128x96");
  writeMapOf({50, 50, 31.5, 23.5, 64, 48}, tmp.path() / "same_camera.ffmap");
  const auto off = testing::runFlowfusion("run " + shellArg(seq) + " --out " + shellArg(out) + " --map-in " +
                                          shellArg(tmp.path() / "same_camera.ffmap") +
                                          " --set slam.loop_closure=off --quiet");
  EXPECT_EQ(off.status, 2) << off.output;
  EXPECT_NE(off.output.find("needs loop closure"), std::string::npos) << off.output;
  // Into the map's own run folder: refused, its files untouched even with --overwrite.
  const fs::path run1 = tmp.path() / "run1";
  fs::create_directories(run1);
  fs::copy_file(tmp.path() / "same_camera.ffmap", run1 / kMapFileName);
  const auto into = testing::runFlowfusion("run " + shellArg(seq) + " --out " + shellArg(run1) + " --map-in " +
                                           shellArg(run1) + " --overwrite --quiet");
  EXPECT_EQ(into.status, 2) << into.output;
  EXPECT_NE(into.output.find("is the --map-in map"), std::string::npos) << into.output;
  EXPECT_EQ(std::distance(fs::directory_iterator(run1), fs::directory_iterator{}), 1);
}

}  // namespace
}  // namespace ff
