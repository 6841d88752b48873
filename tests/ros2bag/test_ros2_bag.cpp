// ROS 2 bags: recordings of a small synthetic sequence written by independent writers (the MCAP
// project's npm writer, tests/fixtures/ros2bag/write_mcap.mjs, and Python's sqlite3 with its own
// CDR encoding, write_db3.py) read as the TUM folder of the same frames reads; whole runs on them
// give the folder's trajectory and masks; bad files give InputErrors naming the file and topic.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "flowfusion/core/config.h"
#include "flowfusion/core/error.h"
#include "flowfusion/io/bag_convert.h"
#include "flowfusion/io/bag_source.h"
#include "flowfusion/io/mcap_reader.h"
#include "flowfusion/io/tum_folder_source.h"
#include "flowfusion/pipeline/run.h"
#include "flowfusion/synth/synthetic_scene.h"
#include "testing/run_output.h"
#include "testing/test_util.h"

namespace fs = std::filesystem;

namespace ff {
namespace {

using testing::inputErrorOf;

#ifndef FLOWFUSION_HAVE_ROS2BAG

TEST(Ros2Bag, ABuildWithoutTheLibrariesSaysHowToEnableRos2Bags) {
  EXPECT_FALSE(ros2BagSupportBuilt());
  const std::string message = inputErrorOf([] { openFrameSource("walk.mcap", SequenceOptions{}); });
  EXPECT_NE(message.find("libzstd-dev"), std::string::npos) << message;
  EXPECT_NE(message.find("walk.mcap"), std::string::npos) << message;
}

#else

constexpr double kFolderDepthScale = 5000;  // the synthetic folder's raw units per metre

// A synthetic folder of 6 frames of 160x120 with one moving object (seed 2: segmented from the
// second frame on, so that equal masks say something), and its frames as the writers' manifest:
// raw RGB8, PNG and 16UC1 (little endian) files with their stamps.
struct Fixture {
  ff::testing::TempDir tmp;
  std::string dir, manifest;
  std::vector<FrameEntry> entries;
  Fixture() {
    synth::SynthConfig c;
    c.seed = 2;
    c.frames = 6;
    c.width = 160;
    c.height = 120;
    c.objects = 1;
    const synth::SyntheticScene scene(c);
    dir = (tmp.path() / "seq").string();
    synth::writeSequence(scene, dir);
    const TumSequence seq = TumSequence::open(dir);
    for (size_t i = 0; i < seq.size(); ++i) entries.push_back(seq.entry(i));
    writeManifest(seq.camera());
  }

  static nlohmann::json stamp(double t) {
    const auto us = static_cast<int64_t>(std::llround(t * 1e6));
    return {{"sec", us / 1000000}, {"nsec", (us % 1000000) * 1000}};
  }

  void writeManifest(const CameraIntrinsics& camera) {
    const fs::path root = tmp.path() / "raw";
    fs::create_directories(root);
    nlohmann::json frames = nlohmann::json::array();
    for (size_t i = 0; i < entries.size(); ++i) {
      const std::string n = std::to_string(i);
      const cv::Mat bgr = cv::imread(entries[i].rgb_path, cv::IMREAD_UNCHANGED);
      const cv::Mat depth = cv::imread(entries[i].depth_path, cv::IMREAD_UNCHANGED);
      cv::Mat rgb;
      cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
      std::ofstream(root / ("rgb" + n + ".bin"), std::ios::binary)
          .write(reinterpret_cast<const char*>(rgb.data), std::streamsize(rgb.total() * rgb.elemSize()));
      std::ofstream(root / ("depth" + n + ".bin"), std::ios::binary)
          .write(reinterpret_cast<const char*>(depth.data), std::streamsize(depth.total() * depth.elemSize()));
      fs::copy_file(entries[i].rgb_path, root / ("rgb" + n + ".png"));
      frames.push_back({{"rgb_stamp", stamp(entries[i].rgb_timestamp)},
                        {"depth_stamp", stamp(entries[i].depth_timestamp)},
                        {"rgb", "rgb" + n + ".bin"}, {"png", "rgb" + n + ".png"}, {"depth", "depth" + n + ".bin"}});
    }
    nlohmann::json m = {{"camera", {{"fx", camera.fx}, {"fy", camera.fy}, {"cx", camera.cx}, {"cy", camera.cy},
                                    {"width", camera.width}, {"height", camera.height}}},
                        {"frames", frames}};
    manifest = (root / "manifest.json").string();
    std::ofstream(manifest) << m.dump();
  }
};

const Fixture& fixture() {
  static const Fixture f;
  return f;
}

bool haveMcapWriter() { return fs::exists(fs::path(FLOWFUSION_MCAP_WRITER).parent_path() / "node_modules"); }

#define REQUIRE_MCAP_WRITER()                                                                              \
  if (!haveMcapWriter())                                                                                   \
  GTEST_SKIP() << "the MCAP fixture writer's node_modules is missing (npm ci failed or npm is absent; see " \
               << FLOWFUSION_MCAP_WRITER << ")"

void writeMcap(const std::string& out, const std::string& args = "") {
  const auto r = ff::testing::runShell("node '" + std::string(FLOWFUSION_MCAP_WRITER) + "' '" + fixture().manifest +
                                       "' '" + out + "' " + args);
  ASSERT_EQ(r.status, 0) << r.output;
}

void writeDb3(const std::string& out, const std::string& args = "") {
  const auto r = ff::testing::runShell("python3 '" + std::string(FLOWFUSION_DB3_WRITER) + "' '" + fixture().manifest +
                                       "' '" + out + "' " + args);
  ASSERT_EQ(r.status, 0) << r.output;
}

// Options under which a bag of the folder's frames reads as the folder does (the ground truth
// gives the first pose).
SequenceOptions bagOptions() {
  SequenceOptions o;
  o.bag.depth_scale = kFolderDepthScale;
  o.bag.groundtruth = fixture().dir + "/groundtruth.txt";
  return o;
}

void expectSameFrames(FrameSource& bag, FrameSource& dir, const std::string& what) {
  ASSERT_EQ(bag.remaining(), dir.remaining()) << what;
  EXPECT_EQ(bag.camera().fx, dir.camera().fx) << what;
  EXPECT_EQ(bag.camera().width, dir.camera().width) << what;
  while (auto a = dir.next()) {
    const auto b = bag.next();
    ASSERT_TRUE(b.has_value()) << what;
    EXPECT_EQ(b->timestamp, a->timestamp) << what;
    EXPECT_EQ(b->depth_timestamp, a->depth_timestamp) << what;
    EXPECT_EQ(cv::norm(b->color, a->color, cv::NORM_INF), 0) << what;
    EXPECT_EQ(cv::norm(b->depth, a->depth, cv::NORM_INF), 0) << what;
  }
  EXPECT_FALSE(bag.next().has_value()) << what;
}

void expectReadsAsTheFolder(const std::string& path, const std::string& what) {
  const auto bag = openFrameSource(path, bagOptions());
  TumFolderSource dir(TumSequence::open(fixture().dir));
  expectSameFrames(*bag, dir, what);
}

TEST(Ros2Bag, McapInEveryChunkCompressionReadsAsTheFolder) {
  REQUIRE_MCAP_WRITER();
  ff::testing::TempDir tmp;
  for (const std::string compression : {"zstd", "lz4", "none"})
    for (const std::string color : {"rgb8", "png"}) {
      const std::string path = (tmp.path() / (compression + color + ".mcap")).string();
      writeMcap(path, "--compression " + compression + " --color " + color);
      expectReadsAsTheFolder(path, compression + " " + color);
    }
}

TEST(Ros2Bag, McapWithoutSummaryIsScannedAndACutShortOneReadsItsWholeChunks) {
  REQUIRE_MCAP_WRITER();
  ff::testing::TempDir tmp;
  const std::string path = (tmp.path() / "nosummary.mcap").string();
  writeMcap(path, "--no-summary");
  expectReadsAsTheFolder(path, "no summary");
  const std::string cut = (tmp.path() / "cut.mcap").string();
  writeMcap(cut);
  fs::resize_file(cut, fs::file_size(cut) * 6 / 10);  // a recording stopped by a crash
  const auto bag = openFrameSource(cut, bagOptions());
  ASSERT_TRUE(bag->remaining().has_value());
  EXPECT_GT(*bag->remaining(), 0u);
  EXPECT_LT(*bag->remaining(), fixture().entries.size());
  TumFolderSource dir(TumSequence::open(fixture().dir));
  while (auto b = bag->next()) {
    const auto a = dir.next();
    EXPECT_EQ(b->timestamp, a->timestamp);
    EXPECT_EQ(cv::norm(b->depth, a->depth, cv::NORM_INF), 0);
  }
}

TEST(Ros2Bag, Db3LittleAndBigEndianReadsAsTheFolder) {
  ff::testing::TempDir tmp;
  for (const std::string flags : {"", "--big-endian"}) {
    const std::string path = (tmp.path() / ("bag" + std::to_string(flags.size()) + ".db3")).string();
    writeDb3(path, flags);
    expectReadsAsTheFolder(path, "db3 " + flags);
  }
}

TEST(Ros2Bag, ARosbag2FolderReadsItsFilesInOrderAndConverts) {
  REQUIRE_MCAP_WRITER();
  ff::testing::TempDir tmp;
  const fs::path bag = tmp.path() / "walk";
  fs::create_directories(bag);
  writeMcap((bag / "walk_0.mcap").string(), "--frames 0:2");
  writeMcap((bag / "walk_1.mcap").string(), "--frames 3:5 --compression lz4");
  std::ofstream(bag / "metadata.yaml") << "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: mcap\n"
                                          "  relative_file_paths:\n    - walk_0.mcap\n    - walk_1.mcap\n"
                                          "  compression_format: \"\"\n  compression_mode: \"\"\n";
  expectReadsAsTheFolder(bag.string(), "folder");
  const std::string out = (tmp.path() / "converted").string();
  const BagConversion c = convertBagToTum(bag.string(), out, bagOptions());
  EXPECT_EQ(c.frames, fixture().entries.size());
  TumFolderSource converted(TumSequence::open(out));
  TumFolderSource dir(TumSequence::open(fixture().dir));
  expectSameFrames(converted, dir, "converted folder");
}

using testing::RunOutput;
using testing::expectSameRun;
using testing::runOn;

TEST(Ros2Bag, RunsOnMcapAndDb3GiveTheFoldersTrajectoryAndMasks) {
  REQUIRE_MCAP_WRITER();
  ff::testing::TempDir tmp;
  TumFolderSource dir(TumSequence::open(fixture().dir));
  const RunOutput reference = runOn(dir);
  size_t dynamic = 0;
  for (const cv::Mat& m : reference.masks) dynamic += cv::countNonZero(m);
  EXPECT_GT(dynamic, 0u) << "the scene's object should be segmented somewhere";
  const std::string mcap = (tmp.path() / "run.mcap").string(), db3 = (tmp.path() / "run.db3").string();
  writeMcap(mcap);
  writeDb3(db3, "--big-endian");
  for (const std::string& path : {mcap, db3}) {
    const auto bag = openFrameSource(path, bagOptions());
    expectSameRun(reference, runOn(*bag), path);
  }
}

TEST(Ros2Bag, TheCommandLineRunsAndConvertsRos2Bags) {
  REQUIRE_MCAP_WRITER();
  ff::testing::TempDir tmp;
  const std::string mcap = (tmp.path() / "walk.mcap").string(), db3 = (tmp.path() / "walk.db3").string();
  writeMcap(mcap);
  writeDb3(db3);
  const std::string out = (tmp.path() / "run").string();
  const auto run = ff::testing::runFlowfusion("run '" + mcap + "' --out '" + out + "' --no-map --depth-scale 5000");
  ASSERT_EQ(run.status, 0) << run.output;
  EXPECT_EQ(readTrajectory(out + "/trajectory.txt").size(), fixture().entries.size());
  const std::string converted = (tmp.path() / "converted").string();
  const auto convert = ff::testing::runFlowfusion("convert '" + db3 + "' '" + converted + "' --depth-scale 5000");
  ASSERT_EQ(convert.status, 0) << convert.output;
  EXPECT_NE(convert.output.find("wrote 6 frames (/camera/rgb/image_color, /camera/depth/image)"), std::string::npos)
      << convert.output;
  EXPECT_EQ(TumSequence::open(converted).size(), fixture().entries.size());
}

// What the MCAP project's reader (read_mcap.mjs) finds in a file.
nlohmann::json readBackWithMcapCore(const std::string& path) {
  const std::string reader = (fs::path(FLOWFUSION_MCAP_WRITER).parent_path() / "read_mcap.mjs").string();
  const auto r = ff::testing::runShell("node '" + reader + "' '" + path + "' 2>&1");
  EXPECT_EQ(r.status, 0) << r.output;
  return nlohmann::json::parse(r.output.substr(0, r.output.find('\n')));
}

TEST(Ros2Bag, RunMcapOutputIsReadBackByTheMcapProjectsReader) {
  REQUIRE_MCAP_WRITER();
  ff::testing::TempDir tmp;
  const std::string out = (tmp.path() / "run").string(), mcap = (tmp.path() / "run.mcap").string();
  const auto run = ff::testing::runFlowfusion("run '" + fixture().dir + "' --out '" + out + "' --mcap '" + mcap + "'");
  ASSERT_EQ(run.status, 0) << run.output;
  EXPECT_NE(run.output.find(mcap), std::string::npos) << "the summary lists the MCAP file: " << run.output;
  const nlohmann::json got = readBackWithMcapCore(mcap);
  const size_t n = fixture().entries.size();
  const std::map<std::string, std::pair<std::string, size_t>> expected = {
      {"/camera/pose", {"foxglove.PoseInFrame", n}},         {"/tf", {"foxglove.FrameTransform", n}},
      {"/camera/path", {"foxglove.PosesInFrame", 1}},        {"/camera/color", {"foxglove.RawImage", n}},
      {"/camera/mask", {"foxglove.RawImage", n}},            {"/camera/depth", {"foxglove.RawImage", n}},
      {"/camera/calibration", {"foxglove.CameraCalibration", 1}}, {"/map", {"foxglove.PointCloud", 1}}};
  ASSERT_EQ(got["channels"].size(), expected.size()) << got["channels"].dump();
  size_t messages = 0;
  for (const auto& [topic, want] : expected) {
    const nlohmann::json& c = got["channels"][topic];
    EXPECT_EQ(c["schema"], want.first) << topic;
    EXPECT_EQ(c["schema_encoding"], "jsonschema") << topic;
    EXPECT_EQ(c["encoding"], "json") << topic;
    EXPECT_EQ(c["messages"].get<size_t>(), want.second) << topic;
    messages += want.second;
  }
  EXPECT_EQ(got["statistics_messages"].get<size_t>(), messages);
  EXPECT_GE(got["chunks"].get<size_t>(), 1u);
  const Trajectory trajectory = readTrajectory(out + "/trajectory.txt");
  ASSERT_EQ(got["poses"].size(), trajectory.size());
  for (size_t i = 0; i < trajectory.size(); ++i) {
    const std::vector<double> p = got["poses"][i].get<std::vector<double>>();  // t, x y z, qx qy qz qw
    const SE3 T = poseFromTranslationQuaternion(Eigen::Vector3d(p[1], p[2], p[3]), Eigen::Quaterniond(p[7], p[4], p[5], p[6]));
    EXPECT_NEAR(p[0], trajectory[i].timestamp, 1e-6) << i;
    // trajectory.txt holds 7 significant digits; the MCAP the doubles themselves
    EXPECT_LT((T.matrix() - trajectory[i].T_world_cam.matrix()).cwiseAbs().maxCoeff(), 1e-6) << i;
  }
  // Our own reader finds the same through the summary's chunk indexes.
  McapReader ours(mcap);
  EXPECT_TRUE(ours.indexed());
  EXPECT_EQ(ours.channels().size(), expected.size());

  // convert-results writes the finished run folder as the same channels and poses.
  const std::string again = (tmp.path() / "again.mcap").string();
  const auto convert = ff::testing::runFlowfusion("convert-results '" + out + "' '" + again + "'");
  ASSERT_EQ(convert.status, 0) << convert.output;
  const nlohmann::json converted = readBackWithMcapCore(again);
  for (const auto& [topic, want] : expected)
    EXPECT_EQ(converted["channels"][topic]["messages"].get<size_t>(), want.second) << "convert-results " << topic;
  ASSERT_EQ(converted["poses"].size(), got["poses"].size());
  for (size_t i = 0; i < trajectory.size(); ++i) {
    const std::vector<double> p = converted["poses"][i].get<std::vector<double>>();
    const SE3 T = poseFromTranslationQuaternion(Eigen::Vector3d(p[1], p[2], p[3]), Eigen::Quaterniond(p[7], p[4], p[5], p[6]));
    EXPECT_EQ(p[0], got["poses"][i][0].get<double>()) << i;
    EXPECT_LT((T.matrix() - trajectory[i].T_world_cam.matrix()).cwiseAbs().maxCoeff(), 1e-9) << i;
  }
  const auto not_a_run = ff::testing::runFlowfusion("convert-results '" + fixture().dir + "' '" + again + "'");
  EXPECT_EQ(not_a_run.status, 2) << not_a_run.output;
  EXPECT_NE(not_a_run.output.find("summary.json"), std::string::npos) << not_a_run.output;
}

void expectRefused(const std::string& path, const std::vector<std::string>& parts, bool on_read = false) {
  const std::string message = inputErrorOf([&] {
    const auto bag = openFrameSource(path, bagOptions());
    while (on_read && bag->next()) {
    }
  });
  EXPECT_NE(message.find(path), std::string::npos) << message;
  for (const auto& part : parts) EXPECT_NE(message.find(part), std::string::npos) << message;
}

// A copy of `path` with byte `at` changed.
std::string withByte(const std::string& path, const std::string& out, uint64_t at, char value) {
  fs::copy_file(path, out);
  std::fstream f(out, std::ios::in | std::ios::out | std::ios::binary);
  f.seekp(std::streamoff(at));
  f.put(value);
  return out;
}

TEST(Ros2Bag, BadMcapFilesAreInputErrorsNamingFileAndTopic) {
  REQUIRE_MCAP_WRITER();
  ff::testing::TempDir tmp;
  const std::string good = (tmp.path() / "good.mcap").string();
  writeMcap(good, "--compression none");
  expectRefused(withByte(good, (tmp.path() / "v1.mcap").string(), 5, '1'), {"version '1'"});
  // A byte inside the first chunk's images: the chunk's CRC no longer matches.
  expectRefused(withByte(good, (tmp.path() / "crc.mcap").string(), fs::file_size(good) / 4, '\x5a'),
                {"CRC", "/camera/color/image_raw"});
  const std::string tiny = (tmp.path() / "tiny.mcap").string();
  fs::copy_file(good, tiny);
  fs::resize_file(tiny, 4);
  expectRefused(tiny, {"not an MCAP file"});
  const std::string fifo = (tmp.path() / "pipe.mcap").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  expectRefused(fifo, {"is not a regular file"});
  expectRefused((tmp.path() / "absent.mcap").string(), {"does not exist"});
  const std::string wrong = (tmp.path() / "wrong.mcap").string();
  writeMcap(wrong, "--wrong-schema");
  expectRefused(wrong, {"/camera/color/image_raw", "schema sensor_msgs/msg/Image"});
}

TEST(Ros2Bag, BadDb3FilesAreInputErrorsNamingFileAndTopic) {
  ff::testing::TempDir tmp;
  const std::string wrong = (tmp.path() / "wrong.db3").string();
  writeDb3(wrong, "--wrong-schema");
  expectRefused(wrong, {"no table topics"});
  const std::string short_depth = (tmp.path() / "short.db3").string();
  writeDb3(short_depth, "--short-depth");
  expectRefused(short_depth, {"/camera/depth/image#0", "holds 19200 bytes"}, true);
  const std::string text = (tmp.path() / "notes.db3").string();
  std::ofstream(text) << "not a database, but long enough to have been one once ......................\n";
  expectRefused(text, {});
}

#endif  // FLOWFUSION_HAVE_ROS2BAG

}  // namespace
}  // namespace ff
