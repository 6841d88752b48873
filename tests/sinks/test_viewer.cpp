// `run --show`'s viewer: without a display it says so and the run goes on; under Xvfb (skipped with
// a message when Xvfb is absent) its window opens and shows every frame.
#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <thread>

#include "flowfusion/io/frame_source.h"
#include "flowfusion/io/tum_sequence.h"
#include "flowfusion/pipeline/run.h"
#include "flowfusion/sinks/viewer_sink.h"
#include "testing/test_util.h"

namespace fs = std::filesystem;

namespace ff {
namespace {

constexpr int kFrames = 6;

class ViewerTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new testing::TempDir();
    const auto r = testing::runFlowfusion("synth " + seq() + " --frames " + std::to_string(kFrames) +
                                          " --width 160 --height 120 --objects 1 --seed 2");
    ASSERT_EQ(r.status, 0) << r.output;
  }
  static void TearDownTestSuite() { delete dir_; }
  static std::string seq() { return (dir_->path() / "seq").string(); }

  static RunSummary runWith(ViewerSink& viewer) {
    const auto source = openFrameSource(seq(), SequenceOptions{});
    return runSequence(*source, SystemConfig{}, {&viewer});
  }
  static testing::TempDir* dir_;
};
testing::TempDir* ViewerTest::dir_ = nullptr;

TEST_F(ViewerTest, WithoutADisplayItSaysSoAndTheRunGoesOn) {
  const std::string display = std::getenv("DISPLAY") ? std::getenv("DISPLAY") : "";
  unsetenv("DISPLAY");
  unsetenv("WAYLAND_DISPLAY");
  ViewerSink viewer;
  const RunSummary s = runWith(viewer);
  if (!display.empty()) setenv("DISPLAY", display.c_str(), 1);
  EXPECT_TRUE(s.complete);
  EXPECT_EQ(s.frames, static_cast<size_t>(kFrames));
  EXPECT_EQ(viewer.framesShown(), 0u);
  ASSERT_EQ(s.notes.size(), 1u);
  EXPECT_NE(s.notes[0].find("no display"), std::string::npos) << s.notes[0];
}

TEST_F(ViewerTest, UnderXvfbTheWindowShowsEveryFrame) {
  if (!fs::exists("/usr/bin/Xvfb")) GTEST_SKIP() << "Xvfb is not installed (apt-get install xvfb); skipping";
  const std::string number = std::to_string(90 + ::getpid() % 100), name = ":" + number;
  const pid_t xvfb = fork();
  ASSERT_GE(xvfb, 0);
  if (xvfb == 0) {
    execl("/usr/bin/Xvfb", "Xvfb", name.c_str(), "-screen", "0", "1280x800x24", "-nolisten", "tcp", (char*)nullptr);
    _exit(127);
  }
  const fs::path socket = "/tmp/.X11-unix/X" + number;
  for (int i = 0; i < 100 && !fs::exists(socket); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  ASSERT_TRUE(fs::exists(socket)) << "Xvfb did not start";
  const std::string old = std::getenv("DISPLAY") ? std::getenv("DISPLAY") : "";
  setenv("DISPLAY", name.c_str(), 1);
  ViewerSink viewer;
  const RunSummary s = runWith(viewer);
  kill(xvfb, SIGTERM);
  if (old.empty()) unsetenv("DISPLAY");
  else setenv("DISPLAY", old.c_str(), 1);
  EXPECT_TRUE(s.complete);
  EXPECT_EQ(viewer.framesShown(), static_cast<size_t>(kFrames));
  EXPECT_TRUE(s.notes.empty());
  const cv::Mat& shown = viewer.lastImage();
  ASSERT_FALSE(shown.empty());
  EXPECT_EQ(shown.rows, ViewerOptions{}.panel_height_px);
  EXPECT_EQ(shown.cols, 400 + 400 + 300);  // 160x120 frames at 300 px high, twice, and the square map
}

}  // namespace
}  // namespace ff
