// Loop closure in the system: a camera turning on the spot in a synthetic room comes back to its
// first view; the loop is found, the trajectory after the closure stays on the truth, and two runs
// give the same poses whatever the background thread's timing.
#include <gtest/gtest.h>

#include <cstdio>
#include <memory>

#include "flowfusion/pipeline/flowfusion_system.h"
#include "flowfusion/synth/synthetic_scene.h"

namespace ff {
namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr int kFrames = 140;       // 3 degrees a frame: 420 degrees
constexpr double kStepDeg = 3.0;

class LoopClosureSystemTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    synth::SynthConfig c;
    c.objects = 0;
    c.width = 320;
    c.height = 240;
    c.frames = kFrames;
    scene_ = std::make_unique<synth::SyntheticScene>(c);
  }
  static void TearDownTestSuite() { scene_.reset(); }

  static SE3 truth(int i) {
    SE3 T = scene_->cameraPose(0);
    T.linear() = Eigen::AngleAxisd(i * kStepDeg * kDeg, Eigen::Vector3d::UnitZ()).toRotationMatrix() * T.linear();
    return T;
  }

  struct Run {
    Trajectory tracked, closed;
    int closures = 0, corrections = 0, keyframes = 0;
  };
  static Run run(LoopClosureMode mode, int frames = kFrames) {
    SystemConfig config;
    config.pipeline.segmentation = false;  // a static room: the odometry and the map are enough
    config.odometry.finest_level = 0;
    config.slam.loop_closure = mode;
    config.slam.keyframe_level = 0;
    FlowFusionSystem system(config, scene_->camera(), truth(0));
    for (int i = 0; i < frames; ++i) system.process(scene_->renderAt(truth(i), scene_->timestamp(i)).frame);
    system.finishLoopClosure();
    return {system.trajectory(), system.closedTrajectory(), system.loopClosures(), system.loopCorrections(),
            system.slamKeyframes()};
  }
  static double maxErrorM(const Trajectory& t) {
    double worst = 0;
    for (int i = 0; i < kFrames; ++i) worst = std::max(worst, translationNorm(t[i].T_world_cam.inverse() * truth(i)));
    return worst;
  }

  static inline std::unique_ptr<synth::SyntheticScene> scene_;
};

TEST_F(LoopClosureSystemTest, ClosesTheLoopReproducibly) {
  if (!loopClosureAvailable()) GTEST_SKIP() << "built without Ceres (libceres-dev): loop closure is off";
  const Run a = run(LoopClosureMode::Ferns);
  std::printf("[ measured ] %d keyframes, %d loop edges, %d corrections; largest error tracked %.4f m, after "
              "closure %.4f m\n", a.keyframes, a.closures, a.corrections, maxErrorM(a.tracked), maxErrorM(a.closed));
  EXPECT_GE(a.keyframes, 20);
  EXPECT_GE(a.closures, 1);
  EXPECT_GE(a.corrections, 1);
  EXPECT_LT(maxErrorM(a.closed), 0.02);
  const Run b = run(LoopClosureMode::Ferns);
  ASSERT_EQ(a.closed.size(), b.closed.size());
  for (size_t i = 0; i < a.closed.size(); ++i)
    ASSERT_TRUE(a.closed[i].T_world_cam.isApprox(b.closed[i].T_world_cam, 0)) << "frame " << i;
}

TEST_F(LoopClosureSystemTest, OffKeepsTheTrackedPoses) {
  const Run off = run(LoopClosureMode::Off, 20);
  EXPECT_EQ(off.closures, 0);
  EXPECT_EQ(off.keyframes, 0);
  ASSERT_EQ(off.closed.size(), off.tracked.size());
  for (size_t i = 0; i < off.closed.size(); ++i)
    EXPECT_TRUE(off.closed[i].T_world_cam.isApprox(off.tracked[i].T_world_cam, 0));
}

}  // namespace
}  // namespace ff
