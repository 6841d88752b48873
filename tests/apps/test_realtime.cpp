// `flowfusion run --realtime [--rate R]` through the executable: a replay far faster than the
// system drops frames instead of queueing them, the counts in summary.json add up, the dropped
// frames have neither a pose nor a mask, a stopped live run's counts add up too, and a bad --rate
// is an error naming the option.
#include <gtest/gtest.h>

#include <filesystem>
#include <set>
#include <string>

#include "flowfusion/core/config.h"
#include "flowfusion/io/trajectory_io.h"
#include "flowfusion/pipeline/system_config.h"
#include "testing/test_util.h"

namespace ff {
namespace {

namespace fs = std::filesystem;

class RealtimeCommand : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    tmp_ = new testing::TempDir;
    const auto r = testing::runFlowfusion("synth " + seq() + " --frames 20 --width 160 --height 120");
    ASSERT_EQ(r.status, 0) << r.output;
  }
  static void TearDownTestSuite() { delete tmp_; }
  static std::string seq() { return (tmp_->path() / "seq").string(); }
  static std::string out(const std::string& name) { return (tmp_->path() / name).string(); }
  static testing::TempDir* tmp_;
};
testing::TempDir* RealtimeCommand::tmp_ = nullptr;

std::set<double> recordedStamps(const std::string& seq) {
  std::set<double> stamps;
  for (const auto& pose : readTrajectory(seq + "/groundtruth.txt")) stamps.insert(pose.timestamp);
  return stamps;
}

TEST_F(RealtimeCommand, AFarTooFastReplayDropsFramesAndTheirPosesAndMasks) {
  // 1000 times the recorded speed: a frame every 33 us, far faster than any frame is processed.
  const auto r = testing::runFlowfusion("run " + seq() + " --out " + out("fast") + " --realtime --rate 1000");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("real time: offered 20, processed"), std::string::npos) << r.output;
  const nlohmann::json summary = readJsonFile(out("fast") + "/summary.json");
  const size_t offered = summary["frames_offered"].get<size_t>();
  const size_t processed = summary["frames_processed"].get<size_t>();
  const size_t dropped = summary["frames_dropped"].get<size_t>();
  EXPECT_EQ(offered, 20u);
  EXPECT_EQ(processed + dropped, offered);
  EXPECT_EQ(processed, summary["frames"].get<size_t>());
  EXPECT_GT(dropped, 0u) << "frames arriving while the system is busy must be dropped, not queued";
  EXPECT_GE(summary["latency_ms_p95"].get<double>(), summary["latency_ms_p50"].get<double>());

  const Trajectory trajectory = readTrajectory(out("fast") + "/trajectory.txt");
  ASSERT_EQ(trajectory.size(), processed);
  const std::set<double> recorded = recordedStamps(seq());
  for (const auto& pose : trajectory) EXPECT_EQ(recorded.count(pose.timestamp), 1u) << pose.timestamp;
  size_t masks = 0;
  for (const auto& entry : fs::directory_iterator(out("fast") + "/masks")) masks += entry.path().extension() == ".png";
  EXPECT_EQ(masks, processed) << "a dropped frame has no mask";
}

TEST_F(RealtimeCommand, ALiveRunStartsFromTheLiveFrameBudgetWhichSetStillDecides) {
  const auto live = testing::runFlowfusion("run " + seq() + " --out " + out("live") + " --realtime --rate 1000 --quiet");
  ASSERT_EQ(live.status, 0) << live.output;
  EXPECT_EQ(readJsonFile(out("live") + "/config.json")["pipeline"]["budget_ms"].get<double>(), kLiveBudgetMs);
  const auto none = testing::runFlowfusion("run " + seq() + " --out " + out("none") +
                                           " --realtime --rate 1000 --quiet --set pipeline.budget_ms=0");
  ASSERT_EQ(none.status, 0) << none.output;
  EXPECT_EQ(readJsonFile(out("none") + "/config.json")["pipeline"]["budget_ms"].get<double>(), 0.0);
  const auto offline = testing::runFlowfusion("run " + seq() + " --out " + out("plain") + " --frames 0:1 --quiet");
  ASSERT_EQ(offline.status, 0) << offline.output;
  EXPECT_EQ(readJsonFile(out("plain") + "/config.json")["pipeline"]["budget_ms"].get<double>(), 0.0);
}

TEST_F(RealtimeCommand, AnInterruptedLiveRunsCountsAddUp) {
  // A fifth of the recorded speed (3.2 s): SIGINT arrives once a few masks exist, before the end.
  const std::string dir = out("stopped");
  const std::string script = std::string(FLOWFUSION_APP_PATH) + " run " + seq() + " --out " + dir +
                             " --realtime --rate 0.2 & pid=$!; for i in $(seq 600); do n=$(ls " + dir +
                             "/masks 2>/dev/null | wc -l); [ \"$n\" -ge 3 ] && break; sleep 0.05; done; kill -INT $pid; "
                             "wait $pid";
  const auto r = testing::runShell(script);
  EXPECT_EQ(r.status, 130) << r.output;
  const nlohmann::json summary = readJsonFile(dir + "/summary.json");
  EXPECT_FALSE(summary["complete"].get<bool>());
  const size_t offered = summary["frames_offered"].get<size_t>();
  const size_t processed = summary["frames_processed"].get<size_t>();
  EXPECT_EQ(processed + summary["frames_dropped"].get<size_t>(), offered);
  EXPECT_EQ(readTrajectory(dir + "/trajectory.txt").size(), processed);
}

TEST_F(RealtimeCommand, AnOfflineRunsSummaryHasNoLiveFigures) {
  const auto r = testing::runFlowfusion("run " + seq() + " --out " + out("offline") + " --frames 0:2 --quiet");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_FALSE(readJsonFile(out("offline") + "/summary.json").contains("frames_offered"));
}

TEST_F(RealtimeCommand, ABadRateIsAnErrorNamingTheOption) {
  for (const std::string rate : {"0", "-2", "nan", "inf", "fast"}) {
    const auto r = testing::runFlowfusion("run " + seq() + " --out " + out("bad") + " --realtime --rate " + rate);
    EXPECT_NE(r.status, 0) << rate;
    EXPECT_NE(r.output.find("--rate"), std::string::npos) << rate << ": " << r.output;
    EXPECT_FALSE(fs::exists(out("bad"))) << rate << ": nothing is written before the options are checked";
  }
  const auto r = testing::runFlowfusion("run " + seq() + " --out " + out("bad") + " --rate 2");
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("--rate requires --realtime"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace ff
