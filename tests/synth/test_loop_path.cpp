// The loop camera path (synth --camera-path loop --laps N): N laps at the configured speed, the
// camera back where it started after each, having looked all round the room; a second recording of
// the same room (--path-start, --path-seed) in the same world frame.
#include <gtest/gtest.h>

#include <cmath>

#include "flowfusion/core/error.h"
#include "flowfusion/synth/synthetic_scene.h"

namespace ff::synth {
namespace {

SynthConfig loop(int laps) {
  SynthConfig c;
  c.camera_path = CameraPathKind::Loop;
  c.laps = laps;
  c.camera_speed = 0.5;
  c.objects = 0;
  c.width = 160;
  c.height = 120;
  return c;
}

TEST(LoopPath, LapsSetTheFramesFromTheSpeed) {
  const SyntheticScene scene(loop(3));
  const double lap_s = 2 * M_PI * kLoopRadiusM / 0.5;
  EXPECT_EQ(scene.frameCount(), static_cast<int>(std::round(3 * lap_s * 30)));
}

TEST(LoopPath, ReturnsToItsStartEveryLapAfterLookingAllRound) {
  const SyntheticScene scene(loop(2));
  const double lap_s = 2 * M_PI * kLoopRadiusM / 0.5;
  const double t0 = scene.timestamp(0);
  const SE3 start = scene.cameraPoseAt(t0);
  for (int lap = 1; lap <= 2; ++lap) {
    const SE3 back = scene.cameraPoseAt(t0 + lap * lap_s);
    // Only the hand-held wobble (a few cm, a few degrees) differs.
    EXPECT_LT(translationNorm(start.inverse() * back), 0.12) << "lap " << lap;
    EXPECT_LT(rotationAngleDeg(start.inverse() * back), 15.0) << "lap " << lap;
  }
  const SE3 half = scene.cameraPoseAt(t0 + lap_s / 2);
  EXPECT_GT(translationNorm(start.inverse() * half), 2 * kLoopRadiusM - 0.15);  // across the circle
  EXPECT_GT(rotationAngleDeg(start.inverse() * half), 150.0);                  // looking the other way
}

TEST(LoopPath, TheCoverWindowIsBlankAndTheCameraMovesOn) {
  SynthConfig c = loop(1);
  c.cover_at_s = 1.0;
  c.cover_s = 0.5;
  const SyntheticScene scene(c);
  for (int i : {29, 30, 44, 45}) {
    const SynthFrame f = scene.render(i);
    const bool covered = i >= 30 && i < 45;
    EXPECT_EQ(cv::countNonZero(f.frame.depth) == 0, covered) << "frame " << i;
    EXPECT_EQ(cv::countNonZero(f.frame.intensity) == 0, covered) << "frame " << i;
  }
  EXPECT_GT(translationNorm(scene.cameraPose(30).inverse() * scene.cameraPose(45)), 0.2);
}

TEST(LoopPath, ASecondRecordingIsTheSameRoomInTheSameWorldFrame) {
  SynthConfig first = loop(1), second = loop(1);
  second.path_start_s = 2.0;
  const SyntheticScene a(first), b(second);
  // Starting 2 s along: the first recording's pose 2 s in, exactly.
  EXPECT_TRUE(b.cameraPose(0).isApprox(a.cameraPoseAt(a.timestamp(0) + 2.0), 0));
  // Another wobble: a different path round the same circle.
  second.path_seed = 7;
  const SyntheticScene c(second);
  const SE3 moved = a.cameraPoseAt(a.timestamp(0) + 2.0).inverse() * c.cameraPose(0);
  EXPECT_GT(translationNorm(moved), 0.002);
  EXPECT_LT(translationNorm(moved), 0.15);
  // The same room: from one pose, the same static images (noise is seeded by the time).
  const SE3 T = c.cameraPose(10);
  const SynthFrame fa = a.renderAt(T, c.timestamp(10)), fc = c.renderAt(T, c.timestamp(10));
  EXPECT_EQ(cv::norm(fa.frame.depth, fc.frame.depth, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(fa.frame.color, fc.frame.color, cv::NORM_INF), 0.0);
  second.camera_path = CameraPathKind::Sweep;
  second.laps = 0;
  EXPECT_THROW(SyntheticScene{second}, InputError);  // path_seed needs the loop
}

TEST(LoopPath, LapsWithoutALoopAreRefused) {
  SynthConfig c = loop(2);
  c.camera_path = CameraPathKind::Sweep;
  EXPECT_THROW(SyntheticScene{c}, InputError);
}

}  // namespace
}  // namespace ff::synth
