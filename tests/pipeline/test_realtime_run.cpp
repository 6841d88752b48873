// Runs from live sources (`run --realtime`, a camera, a ROS node): a forced slow stage makes the run
// drop frames instead of queueing them, the counts add up, dropped frames are not in the
// trajectory, a live source that drops nothing gives the offline run's poses, and the figures reach
// the sinks after every frame and the summary at the end. pipeline.budget_ms: a frame past it
// skips its optional parts, a budget never reached changes nothing.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <thread>

#include "flowfusion/core/error.h"
#include "flowfusion/io/live_frame_queue.h"
#include "flowfusion/io/realtime_replay.h"
#include "flowfusion/pipeline/run.h"
#include "flowfusion/synth/synthetic_scene.h"
#include "synth_source.h"
#include "testing/test_util.h"

namespace ff {
namespace {

using testing::SynthSource;

// A stage slower than the camera: each frame holds the run for `stage_ms`. Keeps the stamps it saw.
struct SlowStageSink : ResultSink {
  int stage_ms = 0;
  std::vector<double> stamps;
  void frame(const RgbdFrame& f, const FrameResult&) override {
    stamps.push_back(f.timestamp);
    std::this_thread::sleep_for(std::chrono::milliseconds(stage_ms));
  }
};

TEST(RealtimeRun, AForcedSlowStageDropsFramesInsteadOfQueueing) {
  SynthSource recording(12);
  const std::vector<double> recorded = recording.stamps();
  RealtimeReplay replay(recording, 1.0);
  SlowStageSink slow;
  slow.stage_ms = 100;  // three frame intervals at 30 Hz
  const RunSummary s = runSequence(replay, SystemConfig{}, {&slow});
  ASSERT_TRUE(s.complete) << s.stop_reason;
  ASSERT_TRUE(s.live);
  EXPECT_EQ(s.live->frames_offered, recorded.size());
  EXPECT_EQ(s.live->frames_processed, s.frames);
  EXPECT_EQ(s.live->frames_processed + s.live->frames_dropped, s.live->frames_offered);
  EXPECT_GT(s.live->frames_dropped, 0u) << "a stage three frames long must drop frames";
  ASSERT_EQ(s.trajectory.size(), s.frames) << "one pose per processed frame, none for a dropped one";
  for (size_t i = 0; i < s.trajectory.size(); ++i) {
    EXPECT_EQ(s.trajectory[i].timestamp, slow.stamps[i]);
    EXPECT_EQ(std::count(recorded.begin(), recorded.end(), slow.stamps[i]), 1) << slow.stamps[i];
    if (i > 0) {
      EXPECT_GT(slow.stamps[i], slow.stamps[i - 1]);
    }
  }
  EXPECT_EQ(slow.stamps.back(), recorded.back()) << "the newest frame is never dropped at the end";
  EXPECT_GT(s.live->latency_ms_p95, 0);
  EXPECT_GE(s.live->latency_ms_p95, s.live->latency_ms_p50);
}

// Offers the next recorded frame only once the run has processed the previous one: a live source
// that never has to drop.
struct LockstepSink : ResultSink {
  SynthSource* recording = nullptr;
  LiveFrameQueue* queue = nullptr;
  const LiveFigures* live = nullptr;
  std::vector<LiveFigures> seen;
  void begin(const RunInfo& info) override { live = info.live; }
  void frame(const RgbdFrame&, const FrameResult&) override {
    seen.push_back(*live);
    if (std::optional<RgbdFrame> f = recording->next())
      queue->offer(std::move(*f));
    else
      queue->close();
  }
};

TEST(RealtimeRun, ALiveSourceThatDropsNothingGivesTheOfflineRunsPoses) {
  SynthSource offline_recording(6), live_recording(6);
  const RunSummary offline = runSequence(offline_recording, SystemConfig{}, {});
  LiveFrameQueue queue(live_recording.camera(), "live");
  queue.offer(*live_recording.next());
  LockstepSink lockstep;
  lockstep.recording = &live_recording;
  lockstep.queue = &queue;
  const RunSummary s = runSequence(queue, SystemConfig{}, {&lockstep});
  ASSERT_TRUE(s.live);
  EXPECT_EQ(s.live->frames_offered, 6u);
  EXPECT_EQ(s.live->frames_processed, 6u);
  EXPECT_EQ(s.live->frames_dropped, 0u);
  ASSERT_EQ(s.trajectory.size(), offline.trajectory.size());
  for (size_t i = 0; i < s.trajectory.size(); ++i)
    EXPECT_TRUE(s.trajectory[i].T_world_cam.matrix() == offline.trajectory[i].T_world_cam.matrix()) << "frame " << i;
  ASSERT_EQ(lockstep.seen.size(), 6u);
  for (size_t i = 0; i < lockstep.seen.size(); ++i) {
    EXPECT_EQ(lockstep.seen[i].frames_processed, i + 1) << "the figures are updated before the sinks see a frame";
    EXPECT_EQ(lockstep.seen[i].frames_offered, i + 1);
  }
}

TEST(RealtimeRun, OnlyALiveRunsSummaryHasTheLiveFigures) {
  SynthSource recording(3), live_recording(3);
  const nlohmann::json offline = toJson(runSequence(recording, SystemConfig{}, {}));
  EXPECT_FALSE(offline.contains("frames_offered"));
  RealtimeReplay replay(live_recording, 4.0);
  const nlohmann::json live = toJson(runSequence(replay, SystemConfig{}, {}));
  for (const char* key : {"frames_offered", "frames_processed", "frames_dropped", "latency_ms_p50", "latency_ms_p95"})
    EXPECT_TRUE(live.contains(key)) << key;
  EXPECT_EQ(live["frames_processed"].get<size_t>(), live["frames"].get<size_t>());
  EXPECT_EQ(live["frames_offered"].get<size_t>(), 3u);
}

// Keeps each frame's segmentation rounds.
struct RoundsSink : ResultSink {
  std::vector<int> rounds;
  void frame(const RgbdFrame&, const FrameResult& r) override { rounds.push_back(r.iterations); }
};

TEST(FrameBudget, AFramePastItsBudgetSkipsLaterRoundsAndLeavesItsFusionToTheNext) {
  SynthSource recording(12);
  SystemConfig config;
  config.pipeline.budget_ms = 1e-3;  // every frame is past it
  RoundsSink rounds;
  const RunSummary s = runSequence(recording, config, {&rounds});
  ASSERT_EQ(rounds.rounds.size(), 12u);
  for (size_t i = 1; i < rounds.rounds.size(); ++i) EXPECT_EQ(rounds.rounds[i], 1) << "frame " << i;
  // fusion_every 2: each fusion waits until 4 frames went unfused (frames 2, 6, 10).
  EXPECT_EQ(s.timings.samples("fusion").size(), 3u);
  EXPECT_GT(s.map_surfels, 0u);
}

TEST(FrameBudget, ABudgetNoFrameReachesChangesNothing) {
  SynthSource plain_recording(6), budget_recording(6);
  SystemConfig config;
  config.pipeline.budget_ms = 1e6;
  const RunSummary plain = runSequence(plain_recording, SystemConfig{}, {});
  const RunSummary budget = runSequence(budget_recording, config, {});
  ASSERT_EQ(plain.trajectory.size(), budget.trajectory.size());
  for (size_t i = 0; i < plain.trajectory.size(); ++i)
    EXPECT_TRUE(plain.trajectory[i].T_world_cam.matrix() == budget.trajectory[i].T_world_cam.matrix()) << i;
  EXPECT_EQ(plain.map_surfels, budget.map_surfels);
}

TEST(FrameBudget, ANegativeBudgetIsAnErrorNamingTheSetting) {
  SystemConfig config;
  config.pipeline.budget_ms = -1;
  EXPECT_NE(testing::inputErrorOf([&] { validate(config); }).find("pipeline.budget_ms"), std::string::npos);
}

}  // namespace
}  // namespace ff
