#include <gtest/gtest.h>

#include "flowfusion/core/error.h"
#include "flowfusion/eval/reference_odometry.h"
#include "flowfusion/eval/trajectory_metrics.h"
#include "flowfusion/io/tum_sequence.h"
#include "testing/test_util.h"

namespace ff::eval {
namespace {

TEST(ReferenceOdometry, UnknownKindIsInputError) {
  EXPECT_THROW(ReferenceOdometry("orb", *freiburgPreset(1)), InputError);
}

TEST(ReferenceOdometry, WrongFrameSizeIsInputError) {
  ReferenceOdometry odometry("rgbd", *freiburgPreset(1));
  RgbdFrame frame;
  frame.name = "small.png";
  frame.intensity = cv::Mat(120, 160, CV_32FC1, cv::Scalar(0.5));
  frame.depth = cv::Mat(120, 160, CV_32FC1, cv::Scalar(1.0));
  EXPECT_THROW(odometry.track(frame), InputError);
}

class ReferenceOdometryOnFr1Xyz : public ::testing::TestWithParam<const char*> {};

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
  EXPECT_LT(max_error_m, 0.03) << GetParam();
  const auto ate = computeAte(*sequence.groundtruth(), run.trajectory);
  EXPECT_LT(ate.translation_m.rmse, 0.02) << GetParam();
}

INSTANTIATE_TEST_SUITE_P(Kinds, ReferenceOdometryOnFr1Xyz, ::testing::Values("rgbd", "icp"));

}  // namespace
}  // namespace ff::eval
