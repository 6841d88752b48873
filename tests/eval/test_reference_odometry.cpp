#include <gtest/gtest.h>

#include <cmath>

#include "flowfusion/core/error.h"
#include "flowfusion/eval/reference_odometry.h"
#include "flowfusion/eval/trajectory_metrics.h"
#include "flowfusion/io/tum_sequence.h"
#include "testing/test_util.h"

namespace ff::eval {
namespace {

TEST(ReferenceOdometry, MethodsAreNamedAsInTheBenchTable) {
  EXPECT_EQ(methodName(ReferenceMethod::RgbdOdometry), "opencv-RgbdOdometry");
  EXPECT_EQ(methodName(ReferenceMethod::RgbdIcpOdometry), "opencv-RgbdICPOdometry");
}

TEST(ReferenceOdometry, WrongFrameSizeIsInputError) {
  ReferenceOdometry odometry(ReferenceMethod::RgbdOdometry, *freiburgPreset(1));
  RgbdFrame frame;
  frame.name = "small.png";
  frame.intensity = cv::Mat(120, 160, CV_32FC1, cv::Scalar(0.5));
  frame.depth = cv::Mat(120, 160, CV_32FC1, cv::Scalar(1.0));
  EXPECT_THROW(odometry.track(frame), InputError);
}

class ReferenceOdometryOnFr1Xyz : public ::testing::TestWithParam<ReferenceMethod> {};

// 30 frames (1 s) of fr1/xyz: the camera moves about 10 cm; frame-to-frame OpenCV odometry
// follows it to within a couple of centimetres (it reaches 3.3 cm ATE over the whole sequence).
TEST_P(ReferenceOdometryOnFr1Xyz, FollowsTheGroundTruthMotion) {
  FF_REQUIRE_SHARED_DATA(dir);
  const auto sequence = TumSequence::open(dir);
  ASSERT_TRUE(sequence.groundtruth());
  const auto run = runReferenceOdometry(GetParam(), sequence, 30);
  ASSERT_EQ(run.trajectory.size(), 30u);
  EXPECT_EQ(run.failures, 0);
  // Started at the ground-truth pose, so positions compare directly, without alignment.
  double max_error_m = 0, travelled_m = 0;
  SE3 T_world_first_gt;
  ASSERT_TRUE(interpolatePose(*sequence.groundtruth(), run.trajectory.front().timestamp, T_world_first_gt));
  for (const auto& p : run.trajectory) {
    SE3 T_world_gt;
    ASSERT_TRUE(interpolatePose(*sequence.groundtruth(), p.timestamp, T_world_gt));
    max_error_m = std::max(max_error_m, (p.T_world_cam.translation() - T_world_gt.translation()).norm());
    travelled_m = std::max(travelled_m, (T_world_gt.translation() - T_world_first_gt.translation()).norm());
  }
  EXPECT_GT(travelled_m, 0.05);
  EXPECT_LT(max_error_m, 0.03) << methodName(GetParam());
  const auto ate = computeAte(*sequence.groundtruth(), run.trajectory);
  EXPECT_LT(ate.translation_m.rmse, 0.02) << methodName(GetParam());
}

INSTANTIATE_TEST_SUITE_P(Methods, ReferenceOdometryOnFr1Xyz,
                         ::testing::Values(ReferenceMethod::RgbdOdometry, ReferenceMethod::RgbdIcpOdometry));

// A textured fronto-parallel wall 1.5 m away, seen by a 160x120 camera.
RgbdFrame wallFrame(double t, double shift_px, bool with_depth) {
  RgbdFrame f;
  f.timestamp = t;
  f.name = "wall";
  f.intensity.create(120, 160, CV_32FC1);
  for (int y = 0; y < 120; ++y)
    for (int x = 0; x < 160; ++x)
      f.intensity.at<float>(y, x) =
          0.5f + 0.25f * std::sin(0.3 * (x + shift_px)) * std::cos(0.23 * y) + 0.1f * std::sin(0.05 * x * y);
  f.depth = cv::Mat(120, 160, CV_32FC1, cv::Scalar(with_depth ? 1.5 : 0.0));
  return f;
}

TEST(ReferenceOdometry, FailedFrameRepeatsThePreviousMotion) {
  const CameraIntrinsics camera{130, 130, 79.5, 59.5, 160, 120};
  ReferenceOdometry odometry(ReferenceMethod::RgbdOdometry, camera);
  odometry.track(wallFrame(0.0, 0, true));
  odometry.track(wallFrame(0.1, 0, true));
  odometry.track(wallFrame(0.2, 0, false));  // no depth: nothing to align
  EXPECT_EQ(odometry.failures(), 1);
  ASSERT_EQ(odometry.trajectory().size(), 3u);
  const SE3 T_1_2 = odometry.trajectory()[1].T_world_cam.inverse() * odometry.trajectory()[2].T_world_cam;
  const SE3 T_0_1 = odometry.trajectory()[0].T_world_cam.inverse() * odometry.trajectory()[1].T_world_cam;
  EXPECT_TRUE(T_1_2.isApprox(T_0_1, 1e-12));
  EXPECT_EQ(odometry.callMs().size(), 2u);
}

}  // namespace
}  // namespace ff::eval
