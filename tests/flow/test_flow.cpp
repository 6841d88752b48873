#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "analytic_scene.h"
#include "flowfusion/core/error.h"
#include "flowfusion/core/image_pyramid.h"
#include "flowfusion/flow/flow_residual.h"
#include "flowfusion/flow/optical_flow.h"

namespace ff {
namespace {

using testing::AnalyticScene;

double medianOf(std::vector<float> v) {
  if (v.empty()) return std::nan("");
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// Finite residual values where mask (if given) equals want.
std::vector<float> valuesWhere(const cv::Mat& r, const cv::Mat& mask, uchar want, int border = 0) {
  std::vector<float> out;
  for (int v = border; v < r.rows - border; ++v)
    for (int u = border; u < r.cols - border; ++u)
      if (std::isfinite(r.at<float>(v, u)) && (mask.empty() || mask.at<uchar>(v, u) == want))
        out.push_back(r.at<float>(v, u));
  return out;
}

SE3 cameraMotion() {
  Vector6d xi;
  xi << 0.03, -0.01, 0.02, 0.01, -0.015, 0.005;  // m, rad
  return expSE3(xi);
}

TEST(OpticalFlowFactory, UnknownNamesAreInputErrors) {
  nlohmann::json j = FlowConfig{};
  j["backend"] = "pwcnet";
  try {
    j.get<FlowConfig>();
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("flow.backend"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("dis"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("farneback"), std::string::npos) << e.what();
  }
  j = FlowConfig{};
  j["dis_preset"] = "slow";
  EXPECT_THROW(j.get<FlowConfig>(), InputError);
  FlowConfig c;
  c.downscale = 3;
  EXPECT_THROW(makeOpticalFlow(c), InputError);
}

TEST(OpticalFlowFactory, ConfigRoundTripsThroughJson) {
  FlowConfig c;
  c.backend = FlowBackend::Farneback;
  c.downscale = 4;
  EXPECT_EQ(nlohmann::json(c)["backend"], "farneback");
  const FlowConfig back = nlohmann::json(c).get<FlowConfig>();
  EXPECT_EQ(back.backend, FlowBackend::Farneback);
  EXPECT_EQ(back.downscale, 4);
  EXPECT_EQ(back.dis_preset, FlowConfig{}.dis_preset);
}

TEST(OpticalFlow, RejectsMismatchedInputs) {
  auto flow = makeOpticalFlow(FlowConfig{});
  EXPECT_THROW(flow->compute(cv::Mat(), cv::Mat()), InputError);
  EXPECT_THROW(flow->compute(cv::Mat::zeros(60, 80, CV_32F), cv::Mat::zeros(60, 81, CV_32F)), InputError);
  EXPECT_THROW(flow->compute(cv::Mat::zeros(60, 80, CV_8U), cv::Mat::zeros(60, 80, CV_8U)), InputError);
}

TEST(EgoFlow, MatchesAnalyticTranslationAndMarksInvalid) {
  const CameraIntrinsics cam{100, 100, 40, 30, 80, 60};
  cv::Mat depth(60, 80, CV_32F, cv::Scalar(2.0f));
  depth.at<float>(10, 10) = 0.f;
  depth.at<float>(11, 11) = std::nanf("");
  SE3 T_b_a = SE3::Identity();
  T_b_a.translation() = Eigen::Vector3d(0.1, -0.05, 0);  // points move +x, -y in B's frame
  const cv::Mat e = egoFlow(depth, cam, T_b_a);
  ASSERT_EQ(e.type(), CV_32FC2);
  EXPECT_NEAR(e.at<cv::Vec2f>(30, 40)[0], 100 * 0.1 / 2.0, 1e-4);
  EXPECT_NEAR(e.at<cv::Vec2f>(5, 70)[1], 100 * -0.05 / 2.0, 1e-4);
  EXPECT_TRUE(std::isnan(e.at<cv::Vec2f>(10, 10)[0]));
  EXPECT_TRUE(std::isnan(e.at<cv::Vec2f>(11, 11)[1]));

  SE3 behind = SE3::Identity();
  behind.translation() = Eigen::Vector3d(0, 0, -3.0);  // every point ends behind camera B
  const cv::Mat eb = egoFlow(depth, cam, behind);
  EXPECT_TRUE(std::isnan(eb.at<cv::Vec2f>(30, 40)[0]));

  EXPECT_THROW(egoFlow(depth, CameraIntrinsics{100, 100, 40, 30, 160, 120}, T_b_a), InputError);
}

// A wall 2 m away at 80x60 without depth at one pixel, seen by a camera moving 4 cm sideways: 2 px
// of ego flow to the right, so the last two columns leave B's image.
struct SidewaysWall {
  CameraIntrinsics cam{100, 100, 39.5, 29.5, 80, 60};
  cv::Mat depth;
  SE3 T_b_a = SE3::Identity();
  cv::Mat e;
  explicit SidewaysWall(cv::Point hole) : depth(60, 80, CV_32F, cv::Scalar(2.0f)) {
    depth.at<float>(hole) = 0.f;
    T_b_a.translation() = Eigen::Vector3d(0.04, 0, 0);
    e = egoFlow(depth, cam, T_b_a);
  }
};

TEST(FlowResidual, NaNWhereEgoFlowInvalidAndCoarseLevelsWork) {
  const SidewaysWall wall({20, 20});
  const cv::Mat& depth = wall.depth;
  const CameraIntrinsics& cam = wall.cam;
  const SE3& T_b_a = wall.T_b_a;
  const cv::Mat& e = wall.e;
  FlowField of{e.clone()};
  of.uv.at<cv::Vec2f>(20, 20) = {1, 1};
  const cv::Mat r = flowResidual(of, e);
  EXPECT_TRUE(std::isnan(r.at<float>(20, 20)));
  EXPECT_NEAR(r.at<float>(30, 30), 0.f, 1e-6);
  // The ego flow is 2 px to the right: the last two columns were out of view in B.
  EXPECT_NEAR(r.at<float>(30, 76), 0.f, 1e-6);
  EXPECT_TRUE(std::isnan(r.at<float>(30, 78)));
  EXPECT_TRUE(std::isnan(r.at<float>(30, 79)));

  // Half resolution: the full-resolution flow is resampled and rescaled to level-1 pixels.
  const cv::Mat e1 = egoFlow(downsampleDepth(depth), cam.atLevel(1), T_b_a);
  const cv::Mat r1 = flowResidual(FlowField{e.clone()}, e1);
  ASSERT_EQ(r1.size(), cv::Size(40, 30));
  EXPECT_LT(medianOf(valuesWhere(r1, cv::Mat(), 0, 2)), 1e-3);
}

// A pixel without depth of its own, tried at the depths around it: a sideways camera move of 5 cm
// gives 2.5 px of flow at 2 m and 5 px at 1 m (fx 100). Flow that one of the surfaces explains has
// no residual; flow 6 px off both keeps at least the distance to the nearer of the two.
TEST(SmallestFlowResidual, TakesTheDepthThatExplainsTheFlowBest) {
  const CameraIntrinsics cam{100, 100, 39.5, 29.5, 80, 60};
  SE3 T_b_a = SE3::Identity();
  T_b_a.translation() = Eigen::Vector3d(0.05, 0, 0);
  const cv::Mat far(60, 80, CV_32F, cv::Scalar(2.f)), near(60, 80, CV_32F, cv::Scalar(1.f));
  FlowField flow{egoFlow(far, cam, T_b_a)};
  egoFlow(near, cam, T_b_a)(cv::Rect(0, 0, 40, 60)).copyTo(flow.uv(cv::Rect(0, 0, 40, 60)));
  cv::Mat own = flow.uv(cv::Rect(0, 40, 80, 20));
  own += cv::Scalar(0.f, 6.f);  // rows 40-59 move down on their own
  cv::Mat gap = near.clone();
  gap(cv::Rect(0, 0, 10, 10)).setTo(0.f);
  const cv::Mat r = smallestFlowResidual(flow, {far, gap}, cam, T_b_a);
  EXPECT_NEAR(r.at<float>(20, 20), 0.f, 1e-4) << "the near surface explains it";
  EXPECT_NEAR(r.at<float>(20, 60), 0.f, 1e-4) << "the far surface explains it";
  EXPECT_NEAR(r.at<float>(5, 5), 2.5f, 1e-3) << "only the far depth is valid there";
  EXPECT_GT(r.at<float>(50, 20), 6.f - 1e-3);
  EXPECT_GT(r.at<float>(50, 60), 6.f - 1e-3);
  const cv::Mat none(60, 80, CV_32F, cv::Scalar(0.f));
  EXPECT_TRUE(std::isnan(smallestFlowResidual(flow, {none}, cam, T_b_a).at<float>(20, 20)));
  EXPECT_THROW(smallestFlowResidual(flow, {}, cam, T_b_a), InputError);
  EXPECT_THROW(smallestFlowResidual(flow, {cv::Mat(30, 40, CV_32F, cv::Scalar(1.f))}, cam, T_b_a), InputError);
}

// A static background seen with a smooth error field (a rotation error, a rolling shutter): the
// optical flow is the ego flow plus an affine field of up to 1.3 px, and a box over a tenth of the
// image moves 6 px more. With the field taken out the background's residual is gone and the box
// keeps its own motion.
TEST(FlowResidual, AnAffineErrorFieldIsTakenOutAndAMoverKeepsItsMotion) {
  const SidewaysWall wall({5, 5});
  const cv::Mat& e = wall.e;
  FlowField of{e.clone()};
  const cv::Rect box(50, 10, 20, 24);  // 480 of 4,800 pixels
  for (int v = 0; v < 60; ++v)
    for (int u = 0; u < 80; ++u) {
      const double x = u / 80.0 - 0.5, y = v / 60.0 - 0.5;
      of.uv.at<cv::Vec2f>(v, u) += cv::Vec2f(static_cast<float>(0.5 + 1.2 * x - 0.3 * y), static_cast<float>(-0.4 + 0.6 * y));
      if (box.contains({u, v})) of.uv.at<cv::Vec2f>(v, u)[0] += 6.f;
    }
  cv::Mat background(60, 80, CV_8U, cv::Scalar(255));
  background(box).setTo(0);
  background.colRange(76, 80).setTo(0);  // out of view in B
  EXPECT_GT(medianOf(valuesWhere(flowResidual(of, e), background, 255)), 0.4) << "the field, counted as motion";
  const cv::Mat r = flowResidualWithoutAffine(of, e, 1.0);
  double worst = 0;
  for (const float x : valuesWhere(r, background, 255)) worst = std::max(worst, static_cast<double>(x));
  // Within 0.1 px: the robust fit still feels the box (a Cauchy weight of 1/37 on each of its pixels).
  EXPECT_LT(worst, 0.1) << "the background without the field";
  EXPECT_NEAR(medianOf(valuesWhere(r, background, 0, 0)), 6.0, 0.05) << "the box's own motion";
  EXPECT_TRUE(std::isnan(r.at<float>(5, 5)));   // no depth
  EXPECT_TRUE(std::isnan(r.at<float>(30, 79)));  // out of view
  EXPECT_THROW(flowResidualWithoutAffine(of, e, 0.0), InputError);
}

// A wall at 2 m with a near surface (0.8 m) over its lower right quarter, the odometry's translation
// 1.5 cm off (as on a blurred frame under fast rotation): the near surface's flow differs from the
// ego flow by 2.4 px, the wall's by 1 px, and no affine field takes both out. The parallax of the
// translation error does; a box on the wall moving 5 px more keeps its motion.
TEST(FlowResidual, ATranslationErrorsParallaxIsTakenOutAndAMoverKeepsItsMotion) {
  const CameraIntrinsics cam{100, 100, 39.5, 29.5, 80, 60};
  cv::Mat depth(60, 80, CV_32F, cv::Scalar(2.0f));
  const cv::Rect near(40, 30, 40, 30), box(8, 8, 16, 16);
  depth(near).setTo(0.8f);
  SE3 T_b_a = expSE3((Vector6d() << 0.01, 0.0, 0.005, 0.0, 0.02, 0.0).finished());
  const FlowField of{egoFlow(depth, cam, T_b_a)};
  of.uv(box) += cv::Scalar(5.f, 0.f);
  T_b_a.translation() += Eigen::Vector3d(0.012, -0.008, 0.005);  // the odometry's error, 1.5 cm
  const cv::Mat e = egoFlow(depth, cam, T_b_a);
  cv::Mat near_mask(depth.size(), CV_8U, cv::Scalar(0));
  near_mask(near).setTo(255);
  cv::Mat wall_mask(depth.size(), CV_8U, cv::Scalar(255));
  wall_mask(near).setTo(0);
  wall_mask(box).setTo(0);
  cv::Mat box_mask(depth.size(), CV_8U, cv::Scalar(0));
  box_mask(box).setTo(255);
  const auto worst = [](const std::vector<float>& v) { return v.empty() ? 0.0 : *std::max_element(v.begin(), v.end()); };
  const cv::Mat affine = flowResidualWithoutAffine(of, e, 1.0);
  EXPECT_GT(std::max(worst(valuesWhere(affine, near_mask, 255)), worst(valuesWhere(affine, wall_mask, 255))), 0.7)
      << "the affine fit leaves 0.8 px on the near surface or the wall";
  const cv::Mat r = flowResidualWithoutPoseError(of, e, depth, cam, 1.0);
  EXPECT_LT(worst(valuesWhere(r, near_mask, 255)), 0.1) << "the near surface";
  EXPECT_LT(worst(valuesWhere(r, wall_mask, 255)), 0.1) << "the wall";
  EXPECT_NEAR(medianOf(valuesWhere(r, box_mask, 255)), 5.0, 0.1) << "the box's own motion";
  EXPECT_THROW(flowResidualWithoutPoseError(of, e, depth, cam, 0.0), InputError);
  EXPECT_THROW(flowResidualWithoutPoseError(of, e, cv::Mat(30, 40, CV_32F, cv::Scalar(1.f)), cam, 1.0),
               InputError);
}

// The one near surface moving 3 px on a wall of one depth: the parallax term alone can take such a
// motion for the camera's translation error. Known movers stay out of the fit and keep their motion.
TEST(FlowResidual, KnownMoversStayOutOfThePoseErrorFit) {
  const CameraIntrinsics cam{100, 100, 39.5, 29.5, 80, 60};
  cv::Mat depth(60, 80, CV_32F, cv::Scalar(2.0f));
  const cv::Rect near(40, 30, 40, 30);
  depth(near).setTo(0.8f);
  const SE3 T_b_a = expSE3((Vector6d() << 0.01, 0.0, 0.005, 0.0, 0.02, 0.0).finished());
  const cv::Mat e = egoFlow(depth, cam, T_b_a);
  FlowField of{e.clone()};
  of.uv(near) += cv::Scalar(3.f, 0.f);
  cv::Mat movers(depth.size(), CV_8U, cv::Scalar(0));
  movers(near).setTo(255);
  EXPECT_LT(medianOf(valuesWhere(flowResidualWithoutPoseError(of, e, depth, cam, 1.0), movers, 255)), 0.1)
      << "unknown, the near mover is taken for the camera's translation error";
  const cv::Mat r = flowResidualWithoutPoseError(of, e, depth, cam, 1.0, movers);
  EXPECT_NEAR(medianOf(valuesWhere(r, movers, 255)), 3.0, 0.05) << "the near mover";
  EXPECT_LT(medianOf(valuesWhere(r, movers, 0)), 0.05) << "the wall";
  EXPECT_THROW(flowResidualWithoutPoseError(of, e, depth, cam, 1.0, cv::Mat(30, 40, CV_8U, cv::Scalar(0))),
               InputError);
}

// The backward flow undoes the forward one except over a patch: there the pixels landing in it are
// flagged, once the gap exceeds the tolerance plus 5 % of the flow.
TEST(InconsistentFlow, FlagsWhereTheBackwardFlowDoesNotBringThePixelBack) {
  const cv::Size size(60, 40);
  const FlowField forward{cv::Mat(size, CV_32FC2, cv::Scalar(3.f, -2.f))};  // |f| 3.61: 5 % is 0.18 px
  FlowField backward{cv::Mat(size, CV_32FC2, cv::Scalar(-3.f, 2.f))};
  EXPECT_EQ(cv::countNonZero(inconsistentFlow(forward, backward, 0.2)), 0);
  backward.uv(cv::Rect(20, 10, 10, 10)).setTo(cv::Scalar(-2.5f, 2.f));  // 0.5 px short
  const cv::Mat strict = inconsistentFlow(forward, backward, 0.2);       // 0.38 px allowed
  EXPECT_EQ(strict.at<uint8_t>(17, 22), 255) << "lands at (25, 15), inside the patch";
  EXPECT_EQ(strict.at<uint8_t>(30, 40), 0) << "lands outside it";
  EXPECT_EQ(cv::countNonZero(inconsistentFlow(forward, backward, 0.4)), 0) << "0.58 px allowed";
  EXPECT_THROW(inconsistentFlow(forward, FlowField{cv::Mat(cv::Size(30, 20), CV_32FC2)}, 0.2), InputError);
  EXPECT_THROW(inconsistentFlow(forward, backward, -1.0), InputError);
}

class FlowOnAnalyticScene : public ::testing::Test {
 protected:
  AnalyticScene scene = AnalyticScene::make(320, 240);
};

TEST_F(FlowOnAnalyticScene, StaticSceneGivesNearZeroResidualWithTrueMotion) {
  const SE3 T_world_b = cameraMotion();
  const auto a = scene.render(SE3::Identity());
  const auto b = scene.render(T_world_b);
  // Full resolution here = the default half-resolution flow of a 640x480 frame.
  FlowConfig c;
  c.downscale = 1;
  const FlowField of = makeOpticalFlow(c)->compute(a.frame.intensity, b.frame.intensity);
  ASSERT_EQ(of.uv.size(), a.frame.depth.size());
  const cv::Mat r = flowResidual(of, egoFlow(a.frame.depth, scene.camera, T_world_b.inverse()));
  // Borders (pixels leaving the image) and the box's disoccluded outline are a small minority.
  const double med = medianOf(valuesWhere(r, cv::Mat(), 0, 8));
  EXPECT_LT(med, 0.3) << "median flow residual " << med << " px";
}

TEST_F(FlowOnAnalyticScene, MovingObjectGivesLargeResidualOnItsPixels) {
  const SE3 T_world_b = cameraMotion();
  const auto a = scene.render(SE3::Identity());
  const auto b = scene.render(T_world_b, Eigen::Vector3d(0.07, 0.0, 0.0));  // ~12 px at 320x240
  for (const FlowBackend backend : {FlowBackend::Dis, FlowBackend::Farneback}) {
    FlowConfig c;
    c.backend = backend;
    const FlowField of = makeOpticalFlow(c)->compute(a.frame.intensity, b.frame.intensity);
    const cv::Mat r = flowResidual(of, egoFlow(a.frame.depth, scene.camera, T_world_b.inverse()));
    cv::Mat inner;  // box pixels away from its outline, where flow is unambiguous
    cv::erode(a.mask, inner, cv::Mat::ones(9, 9, CV_8U));
    const double on_box = medianOf(valuesWhere(r, inner, 255));
    const double background = medianOf(valuesWhere(r, a.mask, 0, 8));
    EXPECT_GT(on_box, 6.0) << enumName(backend);
    EXPECT_LT(background, 0.6) << enumName(backend);
  }
}

TEST(RelativeToFrameError, ScalesOnlyAFrameWhoseMedianErrorExceedsTheTypical) {
  // Also the long baseline's chain brought to a frame pair's noise (scores.long_baseline_noise_px).
  // A frame whose flow failed as a whole (blur): 75 % of the pixels 6 px off, a mover's quarter 24 px.
  cv::Mat r(4, 4, CV_32F, cv::Scalar(6.f));
  r.row(0).setTo(24.f);
  r.at<float>(1, 1) = std::numeric_limits<float>::quiet_NaN();
  EXPECT_DOUBLE_EQ(finiteMedian(r), 6.0);
  const cv::Mat scaled = relativeToFrameError(r, 2.0);
  EXPECT_FLOAT_EQ(scaled.at<float>(2, 2), 2.f);   // the frame's own error comes down to the typical
  EXPECT_FLOAT_EQ(scaled.at<float>(0, 0), 8.f);   // the mover keeps standing out, 4x the frame
  EXPECT_TRUE(std::isnan(scaled.at<float>(1, 1)));
  // A frame whose flow is as good as usual is unchanged, and 0 turns the scaling off.
  const cv::Mat good = r / 6.0;
  EXPECT_EQ(cv::norm(relativeToFrameError(good, 2.0), good, cv::NORM_INF), 0.0);
  EXPECT_FLOAT_EQ(relativeToFrameError(r, 0.0).at<float>(2, 2), 6.f);
  const cv::Mat none(2, 2, CV_32F, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
  EXPECT_TRUE(std::isnan(finiteMedian(none)));
  EXPECT_TRUE(std::isnan(relativeToFrameError(none, 2.0).at<float>(0, 0)));  // no median: as it is
  EXPECT_TRUE(relativeToFrameError(cv::Mat(), 2.0).empty());
}

TEST(HiddenIn, MarksThePointsTheOtherViewSawSomethingNearerAt) {
  // A 32x24 camera before a wall 4 m away; in the other view, 0.5 m to the side, a box 2 m away
  // stands over columns 10-13 (the world is the first view's camera frame).
  const CameraIntrinsics camera{20, 20, 15.5, 11.5, 32, 24};
  const cv::Mat wall(24, 32, CV_32F, cv::Scalar(4.f));
  cv::Mat other = wall.clone();
  other.colRange(10, 14).setTo(2.f);
  SE3 T_other_first = SE3::Identity();
  T_other_first.translation() = Eigen::Vector3d(-0.5, 0, 0);  // the other camera 0.5 m along +x
  const cv::Mat hidden = hiddenIn(wall, other, camera, T_other_first, 0.03);
  // Wall pixel u lands at u - 20 * 0.5 / 4 = u - 2.5 px in the other view, rounded to u - 2: the
  // 3x3 pixels there (u - 3 to u - 1) meet the box's columns for u in 11-16.
  for (int u = 0; u < 32; ++u) {
    const bool behind_box = u >= 11 && u <= 16;
    EXPECT_EQ(hidden.at<uint8_t>(12, u) != 0, behind_box) << "column " << u;
  }
  // The same depth seen again, or a point nearer than what the other view saw, is not hidden.
  EXPECT_EQ(cv::countNonZero(hiddenIn(wall, wall, camera, SE3::Identity(), 0.03)), 0);
  EXPECT_EQ(cv::countNonZero(hiddenIn(cv::Mat(24, 32, CV_32F, cv::Scalar(1.f)), other, camera, SE3::Identity(), 0.03)), 0);
  EXPECT_THROW(hiddenIn(wall, cv::Mat(10, 10, CV_32F, cv::Scalar(1.f)), camera, SE3::Identity(), 0.03), InputError);
}

TEST(LargerResidual, TakesTheLargerWhereBothAreKnownAndKeepsRfsGaps) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const cv::Mat r_F = (cv::Mat_<float>(1, 4) << 1.f, 5.f, nan, 2.f);
  const cv::Mat other = (cv::Mat_<float>(1, 4) << 3.f, 4.f, 9.f, nan);
  const cv::Mat out = largerResidual(r_F, other);
  EXPECT_FLOAT_EQ(out.at<float>(0, 0), 3.f);
  EXPECT_FLOAT_EQ(out.at<float>(0, 1), 5.f);
  EXPECT_TRUE(std::isnan(out.at<float>(0, 2)));  // out of the previous frame's view stays no evidence
  EXPECT_FLOAT_EQ(out.at<float>(0, 3), 2.f);
  EXPECT_EQ(largerResidual(r_F, {}).data, r_F.data);  // no other residual: r_F as it is
  EXPECT_THROW(largerResidual(r_F, cv::Mat(2, 4, CV_32F)), InputError);
}

TEST(ChainFlows, AddsEachStepWhereTheChainHasGotToAndLosesWhatLeavesTheImage) {
  // Step 1 shifts every pixel 2 px right; step 2 shifts the left half of its image 1 px down and
  // the right half 3 px up.
  FlowField right{cv::Mat(8, 10, CV_32FC2, cv::Scalar(2.f, 0.f))};
  FlowField split{cv::Mat(8, 10, CV_32FC2, cv::Scalar(0.f, 1.f))};
  split.uv.colRange(5, 10).setTo(cv::Scalar(0.f, -3.f));
  const FlowField chained = chainFlows({&right, &split});
  const auto at = [&](int u, int v) { return chained.uv.at<cv::Vec2f>(v, u); };
  EXPECT_EQ(at(1, 4), cv::Vec2f(2.f, 1.f));   // reaches column 3, in the left half
  EXPECT_EQ(at(4, 4), cv::Vec2f(2.f, -3.f));  // reaches column 6, in the right half
  EXPECT_TRUE(std::isnan(at(9, 4)[0]));        // reaches column 11, beyond the second image
  EXPECT_EQ(cv::norm(chainFlows({&right}).uv, right.uv, cv::NORM_INF), 0.0);
  EXPECT_THROW(chainFlows({}), InputError);
  FlowField small{cv::Mat(4, 4, CV_32FC2, cv::Scalar(0.f, 0.f))};
  EXPECT_THROW(chainFlows({&right, &small}), InputError);
}

}  // namespace
}  // namespace ff
