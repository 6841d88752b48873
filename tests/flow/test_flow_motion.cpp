#include <gtest/gtest.h>

#include "analytic_scene.h"
#include "flowfusion/core/error.h"
#include "flowfusion/flow/flow_motion.h"
#include "flowfusion/flow/flow_residual.h"

namespace ff {
namespace {

using testing::AnalyticScene;

// A large box in front of the wall covering about a third of the view: the odometry-lock case.
AnalyticScene bigBoxScene() {
  AnalyticScene s = AnalyticScene::make(640, 480);  // ConsensusConfig's pixels are the input's
  s.box_half = Eigen::Vector3d(0.4, 0.4, 0.2);
  s.box_centre = Eigen::Vector3d(0.1, 0.05, 1.5);
  return s;
}

SE3 cameraMotion() { return expSE3((Vector6d() << 0.02, -0.01, 0.015, 0.01, -0.015, 0.005).finished()); }

// The exact flow of frame A when the camera moves by T_world_b and the box's points move rigidly
// by T_box (both in A's frame = the world): background pixels by T_b_a, box pixels by T_b_a * T_box.
FlowField exactTwoMotionFlow(const AnalyticScene& scene, const SE3& T_world_b, const SE3& T_box, cv::Mat& box_mask) {
  const auto a = scene.render(SE3::Identity());
  box_mask = a.mask;
  const cv::Mat background = egoFlow(a.frame.depth, scene.camera, T_world_b.inverse());
  const cv::Mat box = egoFlow(a.frame.depth, scene.camera, T_world_b.inverse() * T_box);
  FlowField f{background.clone()};
  box.copyTo(f.uv, a.mask);
  return f;
}

double translationErrorM(const SE3& a, const SE3& b) { return translationNorm(a.inverse() * b); }

TEST(FlowMotion, RansacFindsTheBackgroundAgainstALargeMovingBox) {
  const AnalyticScene scene = bigBoxScene();
  const SE3 T_world_b = cameraMotion();
  const SE3 T_box = expSE3((Vector6d() << 0.06, 0.0, -0.03, 0.0, 0.04, 0.0).finished());
  cv::Mat box_mask;
  const FlowField flow = exactTwoMotionFlow(scene, T_world_b, T_box, box_mask);
  const auto a = scene.render(SE3::Identity());
  const FlowCorrespondences c = sampleFlowCorrespondences(flow, a.frame.depth, scene.camera, 16);
  ASSERT_GT(c.size(), 500u);
  const double box_fraction = cv::countNonZero(box_mask) / static_cast<double>(box_mask.total());
  ASSERT_GT(box_fraction, 0.25) << "the box must be a large minority for this test";

  ConsensusConfig cfg;
  const FlowMotion m = estimateFlowMotion(c, scene.camera, cfg);
  ASSERT_TRUE(m.ok);
  const SE3 T_b_a = T_world_b.inverse();
  EXPECT_LT(translationErrorM(m.T_b_a, T_b_a), 1e-3);
  EXPECT_LT(rotationAngleDeg(m.T_b_a.inverse() * T_b_a), 0.05);
  // The box's samples are the ones left unexplained, and its own motion explains them.
  const int box_inliers = countFlowInliers(c, scene.camera, T_b_a * T_box, cfg.inlier_px);
  EXPECT_NEAR(m.inliers + box_inliers, static_cast<int>(c.size()), 0.03 * c.size());
  EXPECT_GT(m.inliers, box_inliers);
}

TEST(FlowMotion, RecoversTheCameraMotionFromDisFlow) {
  const AnalyticScene scene = bigBoxScene();
  const SE3 T_world_b = cameraMotion();
  const auto a = scene.render(SE3::Identity());
  // Towards the camera: a sideways move of a box in front of a plane could pass for parallax
  // under some other camera motion, a looming one cannot.
  const auto b = scene.render(T_world_b, Eigen::Vector3d(0.03, 0.0, -0.15));
  FlowConfig fc;
  fc.downscale = 1;
  const FlowField flow = makeOpticalFlow(fc)->compute(a.frame.intensity, b.frame.intensity);
  const FlowCorrespondences c = sampleFlowCorrespondences(flow, a.frame.depth, scene.camera, 16);
  const FlowMotion m = estimateFlowMotion(c, scene.camera, ConsensusConfig{});
  ASSERT_TRUE(m.ok);
  const SE3 T_b_a = T_world_b.inverse();
  EXPECT_LT(translationErrorM(m.T_b_a, T_b_a), 5e-3);
  EXPECT_LT(rotationAngleDeg(m.T_b_a.inverse() * T_b_a), 0.2);
}

TEST(FlowMotion, TooFewSamplesGiveNoMotion) {
  const AnalyticScene scene = AnalyticScene::make(320, 240);
  const auto a = scene.render(SE3::Identity());
  cv::Mat sparse_depth(a.frame.depth.size(), CV_32F, cv::Scalar(0));
  a.frame.depth(cv::Rect(100, 100, 20, 20)).copyTo(sparse_depth(cv::Rect(100, 100, 20, 20)));
  const FlowField flow{egoFlow(a.frame.depth, scene.camera, cameraMotion())};
  const FlowCorrespondences c = sampleFlowCorrespondences(flow, sparse_depth, scene.camera, 16);
  EXPECT_LT(c.size(), 30u);
  EXPECT_FALSE(estimateFlowMotion(c, scene.camera, ConsensusConfig{}).ok);
}

TEST(FlowMotion, SamplingRejectsMismatchedInputsAndBadConfigs) {
  const AnalyticScene scene = AnalyticScene::make(320, 240);
  const cv::Mat depth(240, 320, CV_32F, cv::Scalar(1));
  const FlowField small{cv::Mat(120, 160, CV_32FC2, cv::Scalar(0, 0))};
  EXPECT_THROW(sampleFlowCorrespondences(small, depth, scene.camera, 8), InputError);
  ConsensusConfig bad;
  bad.inlier_px = 0;
  EXPECT_THROW(validate(bad), InputError);
  bad = ConsensusConfig{};
  bad.min_gain = 1.5;
  EXPECT_THROW(validate(bad), InputError);
  bad = ConsensusConfig{};
  bad.grid_step = 0;
  EXPECT_THROW(validate(bad), InputError);
}

}  // namespace
}  // namespace ff
