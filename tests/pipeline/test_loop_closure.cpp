// Loop closure in the system: a camera turning on the spot in a synthetic room comes back to its
// first view; the loop is found, the trajectory after the closure stays on the truth, and two runs
// give the same poses whatever the background thread's timing. Covered for a third of a second on
// its second round, the camera is lost, and found again against the keyframes once it sees; the
// lost frames are bridged in the trajectory after the closure, the live ones say what was tracked. The
// second round's keyframes, in views the first round's cover, keep only their pose-graph nodes.
// Handed poses that slide aside on the second round, the back end pulls them back toward the truth,
// the frames tracked during the slide included.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <optional>
#include <vector>

#include "flowfusion/pipeline/flowfusion_system.h"
#include "flowfusion/slam/loop_closer.h"
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

  static SE3 truth(double i) {
    SE3 T = scene_->cameraPose(0);
    T.linear() = Eigen::AngleAxisd(i * kStepDeg * kDeg, Eigen::Vector3d::UnitZ()).toRotationMatrix() * T.linear();
    return T;
  }

  struct Run {
    Trajectory tracked, closed;
    int closures = 0, corrections = 0, keyframes = 0;
  };
  // Frames [cover_from, cover_to) are blank (no colour, no depth): the view covered; from cover_to on,
  // frame i is seen from pose i + jump (the camera was carried on meanwhile).
  static Run run(LoopClosureMode mode, int frames = kFrames, int cover_from = -1, int cover_to = -1, int jump = 0,
                 std::vector<FrameResult>* results = nullptr, bool cull_covered = true) {
    SystemConfig config;
    config.pipeline.segmentation = false;  // a static room: the odometry and the map are enough
    config.odometry.finest_level = 0;
    config.slam.loop_closure = mode;
    config.slam.keyframe_level = 0;
    config.slam.cull_covered_keyframes = cull_covered;
    FlowFusionSystem system(config, scene_->camera(), truth(0));
    for (int i = 0; i < frames; ++i) {
      RgbdFrame f = scene_->renderAt(truth(i >= cover_to && cover_to >= 0 ? i + jump : i), scene_->timestamp(i)).frame;
      if (i >= cover_from && i < cover_to)
        for (cv::Mat* m : {&f.color, &f.intensity, &f.depth}) m->setTo(0);
      const FrameResult r = system.process(f);
      if (results) results->push_back(r);
    }
    system.finishLoopClosure();
    return {system.trajectory(), system.closedTrajectory(), system.loopClosures(), system.loopCorrections(),
            system.slamKeyframes()};
  }
  static double maxErrorM(const Trajectory& t) {
    double worst = 0;
    for (int i = 0; i < kFrames; ++i) worst = std::max(worst, translationNorm(t[i].T_world_cam.inverse() * truth(i)));
    return worst;
  }

  // The default run, made once for the tests that compare with it.
  static const Run& fernsRun() {
    static const Run r = run(LoopClosureMode::Ferns);
    return r;
  }

  // Covered from 330 to 360 degrees; it sees again at 420 degrees (the first round saw it): carried
  // 60 degrees further than the constant motion would have taken it. Made once for the tests that read it.
  static constexpr int kCoverFrom = 110, kCoverTo = 120, kJump = 20;
  struct CoveredRun {
    Run run;
    std::vector<FrameResult> results;
  };
  static const CoveredRun& coveredRun() {
    static const CoveredRun r = [] {
      CoveredRun c;
      c.run = run(LoopClosureMode::Ferns, kFrames, kCoverFrom, kCoverTo, kJump, &c.results);
      return c;
    }();
    return r;
  }
  // Where the covered run's camera was at frame i: carried on evenly while covered, from the last
  // view before the cover (frame 109, 327 degrees) to the first after it (frame 120, 420 degrees).
  static SE3 coveredTruth(int i) {
    if (i < kCoverFrom) return truth(i);
    if (i >= kCoverTo) return truth(i + kJump);
    return truth(i + kJump * (i - kCoverFrom + 1.0) / (kCoverTo - kCoverFrom + 1));
  }
  static int firstTrackedAfterCover(const std::vector<FrameResult>& results) {
    for (int i = kCoverTo; i < static_cast<int>(results.size()); ++i)
      if (results[i].tracking_ok) return i;
    return -1;
  }

  // The back end alone, handed the frames with the truth's poses except from frame 126 on, where the
  // tracking slides `slide_m` aside over 6 frames (about one keyframe's span: one every 18 degrees)
  // and stays there; the tracker follows each correction, as the system's does.
  struct SlidRun {
    int closures = 0, corrections = 0;
    // Largest error after closure: frames 127-131 (the slide), the others from 120, all from 132.
    double worst_span_m = 0, worst_others_m = 0, worst_after_m = 0;
  };
  static SlidRun handSlidPoses(double slide_m) {
    SystemConfig config;
    config.slam.keyframe_level = 0;
    std::unique_ptr<SlamBackEnd> slam = makeSlamBackEnd(config.slam, config.odometry, scene_->camera());
    const auto slid = [&](int i) {
      SE3 T = truth(i);
      T.translation().x() += slide_m * std::clamp((i - 126) / 6.0, 0.0, 1.0);
      return T;
    };
    constexpr int kTurned = 170;  // 510 degrees: seven keyframes after the slide see the first round's
    SE3 T_new_old = SE3::Identity();
    const auto takeCorrections = [&] {
      while (const std::optional<MapCorrection> c = slam->takeCorrection()) T_new_old = c->T_new_old_current * T_new_old;
    };
    for (int i = 0; i < kTurned; ++i) {
      takeCorrections();
      const RgbdFrame f = scene_->renderAt(truth(i), scene_->timestamp(i)).frame;
      const SE3 T_world_cam = T_new_old * slid(i);
      slam->frameTracked({&f, T_world_cam, T_world_cam, true, cv::Mat(), false});
    }
    slam->finish();
    takeCorrections();
    const Trajectory closed = slam->trajectory();
    SlidRun r{slam->loopClosures(), slam->corrections()};
    for (int i = 120; i < kTurned; ++i) {
      const double e = translationNorm(closed[i].T_world_cam.inverse() * truth(i));
      double& worst = i > 126 && i < 132 ? r.worst_span_m : r.worst_others_m;
      worst = std::max(worst, e);
      if (i >= 132) r.worst_after_m = std::max(r.worst_after_m, e);
    }
    return r;
  }

  static inline std::unique_ptr<synth::SyntheticScene> scene_;
};

TEST_F(LoopClosureSystemTest, ClosesTheLoopReproducibly) {
  if (!loopClosureAvailable()) GTEST_SKIP() << "built without Ceres (libceres-dev): loop closure is off";
  const Run& a = fernsRun();
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

// The tracking slides 6 cm, as people taken for the scene moved it on the synthetic loop. The
// second round's loops pull the keyframes back, the slid
// odometry edge through its robust loss, and the frames tracked during the slide follow the
// keyframes before and after them by how far along they lie. Measured: at most 14.5 mm off the
// truth in the slide's frames (27.2 mm with the keyframe before alone), 22.6 mm elsewhere from
// frame 120 (36.1 mm with quadratic odometry edges), handed 60 mm.
TEST_F(LoopClosureSystemTest, APoseSlideIsPulledBackFramesBetweenKeyframesIncluded) {
  if (!loopClosureAvailable()) GTEST_SKIP() << "built without Ceres (libceres-dev): loop closure is off";
  const SlidRun r = handSlidPoses(0.06);
  std::printf("[ measured ] %d loop edges, %d corrections; largest error after closure: frames 127-131 %.4f m, "
              "the others from 120 %.4f m (handed 0.06 m)\n", r.closures, r.corrections, r.worst_span_m,
              r.worst_others_m);
  EXPECT_GE(r.corrections, 1);
  EXPECT_LT(r.worst_span_m, 0.02);
  EXPECT_LT(r.worst_others_m, 0.03);
}

// A slide of 8 mm: every solve while the frames come moves the keyframes less than
// slam.min_correction_m (1 cm), so none is applied then; the run's end applies the last solve.
// Measured: 4.0 mm off the truth from frame 132 on; without the end's solve the handed 8 mm stay.
TEST_F(LoopClosureSystemTest, ASolveTooSmallToApplyWhileTrackingIsAppliedAtTheEnd) {
  if (!loopClosureAvailable()) GTEST_SKIP() << "built without Ceres (libceres-dev): loop closure is off";
  const SlidRun r = handSlidPoses(0.008);
  std::printf("[ measured ] %d loop edges, %d corrections; largest error after closure from frame 132 %.4f m "
              "(handed 0.008 m)\n", r.closures, r.corrections, r.worst_after_m);
  EXPECT_GE(r.closures, 1);
  EXPECT_EQ(r.corrections, 1);
  EXPECT_LT(r.worst_after_m, 0.006);
}

TEST_F(LoopClosureSystemTest, CoveredKeyframesKeepOnlyTheirNodes) {
  if (!loopClosureAvailable()) GTEST_SKIP() << "built without Ceres (libceres-dev): loop closure is off";
  const Run& culled = fernsRun();
  const Run kept = run(LoopClosureMode::Ferns, kFrames, -1, -1, 0, nullptr, /*cull_covered=*/false);
  std::printf("[ measured ] keyframes kept %d of %d; loop edges %d / %d; largest error after closure %.4f / %.4f m\n",
              culled.keyframes, kept.keyframes, culled.closures, kept.closures, maxErrorM(culled.closed),
              maxErrorM(kept.closed));
  EXPECT_LT(culled.keyframes, kept.keyframes);
  EXPECT_GE(culled.closures, 1);
  EXPECT_LT(maxErrorM(culled.closed), maxErrorM(kept.closed) + 0.005);
}

TEST_F(LoopClosureSystemTest, RelocalizesAfterTheViewWasCovered) {
  if (!loopClosureAvailable()) GTEST_SKIP() << "built without Ceres (libceres-dev): no relocalization";
  const auto& [a, results] = coveredRun();
  const int found = firstTrackedAfterCover(results);
  ASSERT_GE(found, 0) << "never relocalized";
  double worst = 0;
  for (int i = found; i < kFrames; ++i)
    worst = std::max(worst, translationNorm(a.tracked[i].T_world_cam.inverse() * coveredTruth(i)));
  std::printf("[ measured ] tracking ok again %d frames after the view returned (%s); largest error after: %.4f m\n",
              found - kCoverTo, results[found].message.c_str(), worst);
  EXPECT_LE(found - kCoverTo, 30);  // within 1 s at 30 Hz
  EXPECT_LT(worst, 0.05);
  for (int i = kCoverFrom; i < kCoverTo; ++i) EXPECT_FALSE(results[i].tracking_ok) << "frame " << i;
}

// Once found again, the frames lost while covered lie in the trajectory after the closure between the
// last frame tracked before the cover and the first after it (interpolated on SE(3)): the truth, since
// the camera turned evenly meanwhile, and no step between two frames beyond the carried motion's
// (8.5 degrees a frame while covered; as tracked, the return jumps 63 degrees). Their live poses stay
// the constant-velocity guess. Measured: 10.6 mm and 0.41 degrees at most off the truth (bridged
// across 93 degrees), steps at most 5.7 mm and 8.43 degrees (as tracked 62.6 degrees).
TEST_F(LoopClosureSystemTest, BridgesTheLostFramesOnceTrackingIsRegained) {
  if (!loopClosureAvailable()) GTEST_SKIP() << "built without Ceres (libceres-dev): no relocalization";
  const auto& [a, results] = coveredRun();
  const int found = firstTrackedAfterCover(results);
  ASSERT_GE(found, 0) << "never relocalized";
  double worst_m = 0, worst_deg = 0, step_m = 0, step_deg = 0, tracked_step_deg = 0;
  for (int i = kCoverFrom; i < found; ++i) {
    const SE3 T_truth_closed = coveredTruth(i).inverse() * a.closed[i].T_world_cam;
    worst_m = std::max(worst_m, translationNorm(T_truth_closed));
    worst_deg = std::max(worst_deg, rotationAngleDeg(T_truth_closed));
  }
  for (int i = 1; i < kFrames; ++i) {
    const SE3 T_prev_cur = a.closed[i - 1].T_world_cam.inverse() * a.closed[i].T_world_cam;
    step_m = std::max(step_m, translationNorm(T_prev_cur));
    step_deg = std::max(step_deg, rotationAngleDeg(T_prev_cur));
    tracked_step_deg = std::max(
        tracked_step_deg, rotationAngleDeg(a.tracked[i - 1].T_world_cam.inverse() * a.tracked[i].T_world_cam));
  }
  std::printf("[ measured ] lost frames %d-%d bridged: largest error %.4f m, %.2f deg; largest step between frames "
              "%.4f m, %.2f deg (as tracked %.2f deg)\n", kCoverFrom, found - 1, worst_m, worst_deg, step_m, step_deg,
              tracked_step_deg);
  EXPECT_LT(worst_m, 0.02);
  EXPECT_LT(worst_deg, 1.0);
  EXPECT_LT(step_m, 0.01);
  EXPECT_LT(step_deg, 9.5);
  for (int i = kCoverFrom; i < kCoverTo; ++i)
    EXPECT_TRUE(a.tracked[i].T_world_cam.isApprox(results[i].T_world_cam, 1e-9)) << "frame " << i;
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
