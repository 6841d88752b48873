// The run loop and the files sink: sinks see every frame in order, a stop or a failing frame
// ends them with an honest incomplete summary, and the files sink writes what `run` promises.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "flowfusion/core/config.h"
#include "flowfusion/core/error.h"
#include "flowfusion/io/tum_folder_source.h"
#include "flowfusion/sinks/files_sink.h"
#include "flowfusion/pipeline/run.h"
#include "flowfusion/synth/synthetic_scene.h"
#include "synth_source.h"
#include "testing/test_util.h"

namespace ff {
namespace {

namespace fs = std::filesystem;

using testing::SynthSource;

// Records the calls it gets; asks the run to stop after `stop_after` frames.
struct ProbeSink : ResultSink {
  std::vector<std::string> calls;
  std::vector<double> stamps;
  std::atomic<bool>* stop = nullptr;
  size_t stop_after = 0;
  void begin(const RunInfo& info) override { calls.push_back("begin " + info.source); }
  void frame(const RgbdFrame& f, const FrameResult& r) override {
    calls.push_back("frame");
    stamps.push_back(r.timestamp);
    EXPECT_EQ(r.timestamp, f.timestamp);
    if (stop && stamps.size() == stop_after) *stop = true;
  }
  void end(RunSummary& s, const StaticMap* map) override {
    calls.push_back(s.complete ? "end complete" : "end incomplete");
    EXPECT_EQ(s.trajectory.size(), s.frames);
    EXPECT_NE(map, nullptr);
  }
};

TEST(RunSequence, EverySinkSeesEveryFrameInOrder) {
  SynthSource source(4);
  ProbeSink a, b;
  const RunSummary s = runSequence(source, SystemConfig{}, {&a, &b});
  EXPECT_TRUE(s.complete);
  EXPECT_EQ(s.frames, 4u);
  const std::vector<std::string> expected = {"begin synth", "frame", "frame", "frame", "frame", "end complete"};
  EXPECT_EQ(a.calls, expected);
  EXPECT_EQ(b.calls, expected);
  EXPECT_TRUE(std::is_sorted(a.stamps.begin(), a.stamps.end()));
}

TEST(RunSequence, AStopRequestEndsAfterTheCurrentFrame) {
  SynthSource source(6);
  std::atomic<bool> stop{false};
  const char* reason = "interrupted (test)";
  ProbeSink probe;
  probe.stop = &stop;
  probe.stop_after = 2;
  const RunSummary s = runSequence(source, SystemConfig{}, {&probe}, {&stop, &reason});
  EXPECT_FALSE(s.complete);
  EXPECT_EQ(s.stop_reason, "interrupted (test)");
  EXPECT_EQ(s.frames, 2u);
  EXPECT_EQ(s.trajectory.size(), 2u);
  EXPECT_EQ(probe.calls.back(), "end incomplete");
}

// Keeps each frame's pose and mask.
struct ResultsSink : ResultSink {
  std::vector<FrameResult> results;
  void frame(const RgbdFrame&, const FrameResult& r) override { results.push_back(r); }
};

TEST(RunSequence, ReadingAheadChangesNothing) {
  SynthSource ahead_source(6), plain_source(6);
  ResultsSink ahead, plain;
  RunControl no_read_ahead;
  no_read_ahead.prefetch_frames = 0;
  const RunSummary a = runSequence(ahead_source, SystemConfig{}, {&ahead});
  const RunSummary b = runSequence(plain_source, SystemConfig{}, {&plain}, no_read_ahead);
  ASSERT_EQ(a.frames, 6u);
  ASSERT_EQ(b.frames, 6u);
  EXPECT_EQ(a.map_surfels, b.map_surfels);
  for (size_t i = 0; i < 6; ++i) {
    EXPECT_EQ(a.trajectory[i].timestamp, b.trajectory[i].timestamp);
    EXPECT_TRUE(a.trajectory[i].T_world_cam.matrix() == b.trajectory[i].T_world_cam.matrix()) << "frame " << i;
    EXPECT_EQ(cv::norm(ahead.results[i].dynamic_mask, plain.results[i].dynamic_mask, cv::NORM_INF), 0) << "frame " << i;
  }
  EXPECT_EQ(a.timings.samples("fusion").size(), 3u);  // every second frame, the last one's included
  EXPECT_GT(a.frame_ms_median, 0);
}

TEST(FilesSink, WritesResultsAndRefusesANonEmptyFolder) {
  testing::TempDir tmp;
  synth::SynthConfig sc;
  sc.frames = 8;
  sc.width = 320;
  sc.height = 240;
  const std::string seq_dir = (tmp.path() / "seq").string();
  synth::writeSequence(synth::SyntheticScene(sc), seq_dir);
  TumFolderSource source(TumSequence::open(seq_dir));
  FilesSinkOptions options;
  options.out_dir = (tmp.path() / "out").string();
  FilesSink sink(options);
  const RunSummary summary = runSequence(source, SystemConfig{}, {&sink});
  EXPECT_EQ(summary.frames, 8u);

  const fs::path out = options.out_dir;
  for (const char* name : {"trajectory.txt", "config.json", "timings.csv", "summary.json", "map.ply", "map_points.ply"}) {
    EXPECT_TRUE(fs::is_regular_file(out / name)) << name;
    EXPECT_GT(fs::file_size(out / name), 0u) << name;
  }
  int pngs = 0;
  for (const auto& e : fs::directory_iterator(out / "masks")) pngs += e.path().extension() == ".png";
  EXPECT_EQ(pngs, 8);
  EXPECT_EQ(readTrajectory((out / "trajectory.txt").string()).size(), 8u);
  EXPECT_TRUE(readJsonFile((out / "summary.json").string())["complete"].get<bool>());

  TumFolderSource again(TumSequence::open(seq_dir));
  FilesSink second(options);
  EXPECT_THROW(runSequence(again, SystemConfig{}, {&second}), InputError);
}

TEST(FilesSink, AFailingFrameLeavesAMarkedPartialResult) {
  testing::TempDir tmp;
  SynthSource source(6, 3);
  FilesSinkOptions options;
  options.out_dir = (tmp.path() / "out").string();
  FilesSink sink(options);
  EXPECT_THROW(runSequence(source, SystemConfig{}, {&sink}), InputError);
  const nlohmann::json summary = readJsonFile((tmp.path() / "out" / "summary.json").string());
  EXPECT_FALSE(summary["complete"].get<bool>());
  EXPECT_NE(summary["stop_reason"].get<std::string>().find("frame 3: unreadable"), std::string::npos);
  EXPECT_EQ(summary["frames"].get<int>(), 3);
  EXPECT_EQ(readTrajectory((tmp.path() / "out" / "trajectory.txt").string()).size(), 3u);
  EXPECT_FALSE(fs::exists(tmp.path() / "out" / "map.ply"));
}

TEST(FilesSink, ARunTooShortForAMeshSucceedsAndSaysSo) {
  testing::TempDir tmp;
  SynthSource source(1);
  FilesSinkOptions options;
  options.out_dir = (tmp.path() / "out").string();
  FilesSink sink(options);
  const RunSummary s = runSequence(source, SystemConfig{}, {&sink});
  EXPECT_TRUE(s.complete);
  ASSERT_EQ(s.notes.size(), 1u);
  EXPECT_NE(s.notes[0].find("no map written"), std::string::npos);
  const nlohmann::json summary = readJsonFile((tmp.path() / "out" / "summary.json").string());
  EXPECT_EQ(summary["notes"].size(), 1u);
}

// Replaces the output's masks/ folder by a file once the files sink has begun, so every mask
// write fails.
struct BreakMasksSink : ResultSink {
  fs::path masks;
  void begin(const RunInfo&) override {
    fs::remove_all(masks);
    std::ofstream(masks) << "not a folder";
  }
};

// One frame: the failure can only surface in end(); six: in a later frame() or in end().
TEST(FilesSink, AFailedMaskWriteFailsTheRunWithAMarkedPartialResult) {
  for (const int frames : {1, 6}) {
    testing::TempDir tmp;
    SynthSource source(frames);
    FilesSinkOptions options;
    options.out_dir = (tmp.path() / "out").string();
    FilesSink sink(options);
    BreakMasksSink breaker;
    breaker.masks = tmp.path() / "out" / "masks";
    try {
      runSequence(source, SystemConfig{}, {&sink, &breaker});
      ADD_FAILURE() << frames << " frames: a failed mask write must fail the run";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("cannot write mask"), std::string::npos) << e.what();
    }
    const nlohmann::json summary = readJsonFile((tmp.path() / "out" / "summary.json").string());
    EXPECT_FALSE(summary["complete"].get<bool>()) << frames;
    EXPECT_NE(summary["stop_reason"].get<std::string>().find("cannot write mask"), std::string::npos) << frames;
    EXPECT_TRUE(fs::is_regular_file(tmp.path() / "out" / "trajectory.txt")) << frames;
    EXPECT_FALSE(fs::exists(tmp.path() / "out" / "map.ply")) << frames;
  }
}

TEST(FilesSink, AStoppedRunHasTheMaskOfEveryFrameItProcessed) {
  testing::TempDir tmp;
  SynthSource source(8);
  std::atomic<bool> stop{false};
  const char* reason = "interrupted (test)";
  FilesSinkOptions options;
  options.out_dir = (tmp.path() / "out").string();
  FilesSink sink(options);
  ResultsSink results;
  ProbeSink probe;
  probe.stop = &stop;
  probe.stop_after = 5;
  const RunSummary s = runSequence(source, SystemConfig{}, {&sink, &results, &probe}, {&stop, &reason});
  EXPECT_FALSE(s.complete);
  ASSERT_EQ(results.results.size(), 5u);
  for (const FrameResult& r : results.results) {
    const fs::path png = tmp.path() / "out" / "masks" / (timestampName(r.timestamp) + ".png");
    const cv::Mat mask = cv::imread(png.string(), cv::IMREAD_UNCHANGED);
    ASSERT_FALSE(mask.empty()) << png;
    EXPECT_EQ(cv::norm(mask, r.dynamic_mask, cv::NORM_INF), 0) << png;
  }
  EXPECT_EQ(std::distance(fs::directory_iterator(tmp.path() / "out" / "masks"), fs::directory_iterator{}), 5);
  const nlohmann::json summary = readJsonFile((tmp.path() / "out" / "summary.json").string());
  EXPECT_FALSE(summary["complete"].get<bool>());
  EXPECT_EQ(summary["stop_reason"].get<std::string>(), "interrupted (test)");
}

}  // namespace
}  // namespace ff
