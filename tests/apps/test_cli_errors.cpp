// The `flowfusion` executable on bad input: exit status 2 and a message naming the culprit,
// with nothing overwritten. Needs the flowfusion_app target built.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "testing/test_util.h"

namespace fs = std::filesystem;

namespace ff {
namespace {

std::string shellArg(const fs::path& p) { return "'" + p.string() + "'"; }

TEST(CliErrors, RunOnMissingFolder) {
  testing::TempDir tmp;
  const fs::path missing = tmp.path() / "no_such_sequence";
  const auto r = testing::runFlowfusion("run " + shellArg(missing) + " --out " + shellArg(tmp.path() / "out"));
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find(missing.string()), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(tmp.path() / "out"));
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
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("odometry.levels"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(tmp.path() / "out"));
}

TEST(CliErrors, UnknownSetting) {
  testing::TempDir tmp;
  const std::string seq = testing::makeTinySequence(tmp.path() / "seq").string();
  const auto r = testing::runFlowfusion("run " + shellArg(seq) + " --out " + shellArg(tmp.path() / "out") +
                                        " --set nosuch.key=1");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("nosuch"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(tmp.path() / "out"));
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

}  // namespace
}  // namespace ff
