// Runs that stop early or are too short (issue 16, cases 4 and 5), through the executable:
// SIGINT/SIGTERM stop a run after the current frame with its trajectory, masks and an honest
// summary.json, and a one-frame run succeeds and says why it wrote no mesh.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include "flowfusion/core/config.h"
#include "flowfusion/io/trajectory_io.h"
#include "testing/test_util.h"

namespace ff {
namespace {

namespace fs = std::filesystem;

class StoppedRuns : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto r = testing::runFlowfusion("synth " + seq() + " --frames 60 --width 160 --height 120");
    ASSERT_EQ(r.status, 0) << r.output;
  }
  std::string seq() const { return (tmp_.path() / "seq").string(); }
  std::string out() const { return (tmp_.path() / "out").string(); }
  testing::TempDir tmp_;
};

void stopsWith(const std::string& signal, int expected_status, const std::string& seq, const std::string& out) {
  // The signal arrives once a few masks exist, while the run is going on.
  const std::string script = std::string(FLOWFUSION_APP_PATH) + " run " + seq + " --out " + out +
                             " & pid=$!; for i in $(seq 600); do n=$(ls " + out +
                             "/masks 2>/dev/null | wc -l); [ \"$n\" -ge 3 ] && break; sleep 0.05; done; kill -" +
                             signal + " $pid; wait $pid";
  const auto r = testing::runShell(script);
  EXPECT_EQ(r.status, expected_status) << r.output;
  EXPECT_NE(r.output.find("run stopped after"), std::string::npos) << r.output;
  const nlohmann::json summary = readJsonFile(out + "/summary.json");
  EXPECT_FALSE(summary["complete"].get<bool>());
  EXPECT_NE(summary["stop_reason"].get<std::string>().find(signal), std::string::npos) << summary.dump();
  const size_t frames = summary["frames"].get<size_t>();
  EXPECT_GE(frames, 3u);
  EXPECT_LT(frames, 60u);
  EXPECT_EQ(readTrajectory(out + "/trajectory.txt").size(), frames);
  EXPECT_FALSE(fs::exists(out + "/map.ply")) << "an interrupted run exports no map";
}

TEST_F(StoppedRuns, SigintStopsAfterTheCurrentFrameWithAPartialResult) { stopsWith("INT", 130, seq(), out()); }

TEST_F(StoppedRuns, SigtermStopsTheSameWay) { stopsWith("TERM", 143, seq(), out()); }

TEST_F(StoppedRuns, AOneFrameRunSucceedsAndSaysWhyThereIsNoMesh) {
  const auto r = testing::runFlowfusion("run " + seq() + " --out " + out() + " --frames 0:0");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("no map written"), std::string::npos) << r.output;
  const nlohmann::json summary = readJsonFile(out() + "/summary.json");
  EXPECT_TRUE(summary["complete"].get<bool>());
  EXPECT_EQ(summary["frames"].get<int>(), 1);
  EXPECT_EQ(readTrajectory(out() + "/trajectory.txt").size(), 1u);
}

}  // namespace
}  // namespace ff
