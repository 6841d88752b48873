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

SE3 boxMotion() { return expSE3((Vector6d() << 0.06, 0.0, -0.03, 0.0, 0.04, 0.0).finished()); }

// The big box scene's exact two-motion flow (camera and box moving) and its sampled correspondences.
struct TwoMotionCase {
  AnalyticScene scene = bigBoxScene();
  SE3 T_b_a = cameraMotion().inverse();
  cv::Mat box_mask;
  FlowField flow = exactTwoMotionFlow(scene, cameraMotion(), boxMotion(), box_mask);
  cv::Mat depth_a = scene.render(SE3::Identity()).frame.depth;
  FlowCorrespondences c = sampleFlowCorrespondences(flow, depth_a, scene.camera, 16);
};

TEST(FlowMotion, TheSplitRecoversBothMotionsAndTheMoversSamples) {
  const TwoMotionCase t;
  const auto& [scene, T_b_a, box_mask, flow, depth_a, c] = t;
  ASSERT_GT(c.size(), 500u);
  const double box_fraction = cv::countNonZero(box_mask) / static_cast<double>(box_mask.total());
  ASSERT_GT(box_fraction, 0.25) << "the box must be a large minority for this test";
  const FlowMotionSplit split = splitFlowMotions(c, scene.camera, ConsensusConfig{});
  ASSERT_TRUE(split.ok);
  EXPECT_LT(rotationAngleDeg(split.T_b_a_background.inverse() * T_b_a), 0.05);
  EXPECT_LT(translationErrorM(split.T_b_a_background, T_b_a), 1e-3);
  EXPECT_LT(translationErrorM(split.T_b_a_mover, T_b_a * boxMotion()), 1e-3);
  // Each sample in the group of the motion that made its flow.
  int wrong = 0, on_box = 0;
  for (size_t k = 0; k < c.size(); ++k) {
    const Eigen::Vector2d uv = scene.camera.project(Eigen::Vector3d(c.points_a[k].x, c.points_a[k].y, c.points_a[k].z));
    const bool box = box_mask.at<unsigned char>(static_cast<int>(std::lround(uv.y())), static_cast<int>(std::lround(uv.x()))) > 0;
    on_box += box;
    wrong += split.group[k] != (box ? FlowMotionSplit::kMover : FlowMotionSplit::kBackground);
  }
  EXPECT_LT(wrong, 0.03 * c.size());
  EXPECT_GT(split.mover_only.size(), 0.8 * on_box);
}

TEST(FlowMotion, TheMoverIsFoundAndACapturedOdometryIsTold) {
  const TwoMotionCase t;
  const auto& [scene, T_b_a, box_mask, flow, depth_a, c] = t;
  const ConsensusConfig cfg;
  // A correct odometry: the mover is found, the odometry was not captured.
  const auto split = splitFlowAgainst(c, scene.camera, T_b_a, cfg);
  ASSERT_TRUE(split);
  EXPECT_TRUE(showsMover(*split, c, cfg));
  EXPECT_TRUE(showsMoverGroup(*split, c, scene.camera, cfg));
  EXPECT_LT(translationErrorM(split->T_b_a_background, T_b_a), 1e-3);
  EXPECT_FALSE(misledOdometry(c, scene.camera, *split, T_b_a, cfg));
  // One that followed the box: the same split, and a capture.
  const auto followed = splitFlowAgainst(c, scene.camera, T_b_a * boxMotion(), cfg);
  ASSERT_TRUE(followed);
  EXPECT_LT(translationErrorM(followed->T_b_a_background, T_b_a), 1e-3);
  EXPECT_TRUE(misledOdometry(c, scene.camera, *followed, T_b_a * boxMotion(), cfg));
  // Nothing moves: nothing to split off a correct odometry; a wrong one is told by the gain.
  const FlowField still{egoFlow(depth_a, scene.camera, T_b_a)};
  const FlowCorrespondences c_still = sampleFlowCorrespondences(still, depth_a, scene.camera, 16);
  EXPECT_FALSE(splitFlowAgainst(c_still, scene.camera, T_b_a, cfg));
  SE3 wrong = T_b_a;
  wrong.translation() += Eigen::Vector3d(0.05, 0.0, 0.0);
  const auto off = splitFlowAgainst(c_still, scene.camera, wrong, cfg);
  ASSERT_TRUE(off);
  EXPECT_FALSE(showsMover(*off, c_still, cfg));
  EXPECT_TRUE(misledOdometry(c_still, scene.camera, *off, wrong, cfg));
}

// Per sample: on the map where frame A shows the wall, in front of it on the box (the map of a
// scene whose box was seen moving).
std::vector<MapRelation> wallOnMap(const FlowCorrespondences& c, const CameraIntrinsics& camera, const cv::Mat& box_mask) {
  std::vector<MapRelation> relation;
  for (const cv::Point3f& p : c.points_a) {
    const Eigen::Vector2d uv = camera.project(Eigen::Vector3d(p.x, p.y, p.z));
    const bool box = box_mask.at<unsigned char>(static_cast<int>(std::lround(uv.y())), static_cast<int>(std::lround(uv.x())));
    relation.push_back(box ? MapRelation::kInFront : MapRelation::kOnMap);
  }
  return relation;
}

// A box filling most of the view, 1.2 m away before the wall: its exact two-motion flow sampled.
struct LargeBoxCase {
  AnalyticScene scene = [] {
    AnalyticScene s = AnalyticScene::make(640, 480);
    s.box_half = Eigen::Vector3d(0.55, 0.42, 0.2);
    s.box_centre = Eigen::Vector3d(0.05, 0.05, 1.4);
    return s;
  }();
  SE3 T_b_a = cameraMotion().inverse();
  cv::Mat box_mask;
  FlowField flow = exactTwoMotionFlow(scene, cameraMotion(), boxMotion(), box_mask);
  FlowCorrespondences c = sampleFlowCorrespondences(flow, scene.render(SE3::Identity()).frame.depth, scene.camera, 16);
};

TEST(FlowMotion, AMoverFillingMostOfTheViewIsTheMoverWhenTheMapSaysSo) {
  const LargeBoxCase t;
  const auto& [scene, T_b_a, box_mask, flow, c] = t;
  ASSERT_GT(cv::countNonZero(box_mask), 0.52 * box_mask.total()) << "the box must fill most of the view";
  ConsensusConfig cfg;
  cfg.nearer_mover_depth_ratio = 0;  // the roles by size alone
  // Without the map the larger group, the box, is taken for the background, and a correct
  // odometry looks captured.
  const auto by_size = splitFlowAgainst(c, scene.camera, T_b_a, cfg);
  ASSERT_TRUE(by_size);
  EXPECT_LT(translationErrorM(by_size->T_b_a_background, T_b_a * boxMotion()), 1e-3);
  EXPECT_TRUE(misledOdometry(c, scene.camera, *by_size, T_b_a, cfg));
  // Samples on the map are no evidence of a capture.
  const std::vector<MapRelation> relation = wallOnMap(c, scene.camera, box_mask);
  EXPECT_FALSE(misledOdometry(c, scene.camera, *by_size, T_b_a, cfg, relation));
  // With the map the wall is the background.
  const auto by_map = splitFlowAgainst(c, scene.camera, T_b_a, cfg, relation);
  ASSERT_TRUE(by_map);
  EXPECT_LT(translationErrorM(by_map->T_b_a_background, T_b_a), 1e-3);
  EXPECT_LT(translationErrorM(by_map->T_b_a_mover, T_b_a * boxMotion()), 1e-3);
  EXPECT_FALSE(misledOdometry(c, scene.camera, *by_map, T_b_a, cfg, relation));
  // A map that knows nothing there does not decide.
  const std::vector<MapRelation> unknown(c.size(), MapRelation::kUnknown);
  EXPECT_LT(translationErrorM(splitFlowMotions(c, scene.camera, cfg, {}, unknown).T_b_a_background, T_b_a * boxMotion()),
            1e-3);
}

TEST(FlowMotion, OfTwoComparableGroupsTheNearerIsTheMoverWithoutAMap) {
  // The same box over most of the view, with no map to say which motion is the world's (the
  // start: the map is the first frame, box and all): the box lies nearer than 0.75 of the wall's
  // depth and the wall's group holds over 0.6 of the box's samples, so the box is the mover.
  const LargeBoxCase t;
  const auto& [scene, T_b_a, box_mask, flow, c] = t;
  const ConsensusConfig cfg;
  const FlowMotionSplit split = splitFlowMotions(c, scene.camera, cfg);
  ASSERT_TRUE(split.ok);
  EXPECT_LT(translationErrorM(split.T_b_a_background, T_b_a), 1e-3);
  EXPECT_LT(translationErrorM(split.T_b_a_mover, T_b_a * boxMotion()), 1e-3);
  const auto against = splitFlowAgainst(c, scene.camera, T_b_a, cfg);
  ASSERT_TRUE(against);
  EXPECT_FALSE(misledOdometry(c, scene.camera, *against, T_b_a, cfg)) << "a correct odometry is not captured";
  // A smaller box (a third of the view) is the mover by its size, as before.
  const TwoMotionCase small;
  const FlowMotionSplit by_size = splitFlowMotions(small.c, small.scene.camera, cfg);
  EXPECT_LT(translationErrorM(by_size.T_b_a_mover, small.T_b_a * boxMotion()), 1e-3);
}

TEST(FlowMotion, TextureIsTheImagesVariationInItsWeakerDirection) {
  // A uniform patch, a straight edge and a linear ramp have none: along the edge, and across the
  // ramp's gradient, the image is constant and the flow is not in it. A checkerboard of 2-pixel
  // squares varies in every direction.
  cv::Mat uniform(40, 40, CV_32F, cv::Scalar(0.5f));
  EXPECT_NEAR(textureAt(uniform, 20, 20), 0.0, 1e-9);
  cv::Mat edge = uniform.clone();
  edge.colRange(20, 40).setTo(0.9f);
  EXPECT_NEAR(textureAt(edge, 20, 20), 0.0, 1e-6);
  cv::Mat ramp(40, 40, CV_32F);
  for (int v = 0; v < 40; ++v)
    for (int u = 0; u < 40; ++u) ramp.at<float>(v, u) = (4.f * u + 4.f * v) / 255.f;
  EXPECT_NEAR(textureAt(ramp, 20, 20), 0.0, 1e-3);
  cv::Mat checker(40, 40, CV_32F);
  for (int v = 0; v < 40; ++v)
    for (int u = 0; u < 40; ++u) checker.at<float>(v, u) = ((u / 2 + v / 2) % 2) ? 0.6f : 0.4f;
  EXPECT_GT(textureAt(checker, 20, 20), 10.0) << "grey levels per pixel";
}

TEST(FlowMotion, AtTheStartTheLargerGroupIsCountedInItsTexturedSamples) {
  // The box over most of the view, uniform grey (a flat-coloured box at the start, its flow filled
  // in from its outline): with the roles by size alone, the box's group is the larger in all
  // samples, the wall's in the samples where the image is textured, so the wall is the background.
  const LargeBoxCase t;
  const auto& [scene, T_b_a, box_mask, flow, c] = t;
  const auto a = scene.render(SE3::Identity());
  // A fine texture everywhere (sensor noise and print, about 5 grey levels), then the box uniform.
  cv::Mat fine(a.frame.intensity.size(), CV_32F);
  cv::RNG rng(7);
  rng.fill(fine, cv::RNG::NORMAL, 0.0, 0.02);
  const cv::Mat textured_image = a.frame.intensity + fine;
  cv::Mat intensity = textured_image.clone();
  intensity.setTo(0.5f, box_mask);
  ConsensusConfig cfg;
  cfg.nearer_mover_depth_ratio = 0;
  const FlowCorrespondences measured =
      sampleFlowCorrespondences(flow, a.frame.depth, scene.camera, 16, intensity, cfg.start_min_texture);
  ASSERT_EQ(measured.textured.size(), measured.size());
  int textured[2] = {0, 0}, all[2] = {0, 0};  // wall, box
  for (size_t k = 0; k < measured.size(); ++k) {
    const cv::Point3f& p = measured.points_a[k];
    const Eigen::Vector2d uv = scene.camera.project(Eigen::Vector3d(p.x, p.y, p.z));
    const int on_box = box_mask.at<unsigned char>(static_cast<int>(std::lround(uv.y())), static_cast<int>(std::lround(uv.x())))
                           ? 1 : 0;
    ++all[on_box];
    textured[on_box] += measured.textured[k];
  }
  ASSERT_GT(all[1], all[0]) << "the box's samples outnumber the wall's";
  EXPECT_GT(textured[0], 0.9 * all[0]) << "the wall's texture";
  EXPECT_LT(textured[1], 0.2 * all[1]) << "only the box's outline";
  const FlowMotionSplit split = splitFlowMotions(measured, scene.camera, cfg);
  ASSERT_TRUE(split.ok);
  EXPECT_LT(translationErrorM(split.T_b_a_background, T_b_a), 1e-3);
  EXPECT_LT(translationErrorM(split.T_b_a_mover, T_b_a * boxMotion()), 1e-3);
  // Textured as the wall, the box is the larger group again; without the image, by all samples.
  const FlowCorrespondences textured_box =
      sampleFlowCorrespondences(flow, a.frame.depth, scene.camera, 16, textured_image, cfg.start_min_texture);
  EXPECT_LT(translationErrorM(splitFlowMotions(textured_box, scene.camera, cfg).T_b_a_background, T_b_a * boxMotion()),
            1e-3);
  EXPECT_TRUE(c.textured.empty());
  EXPECT_LT(translationErrorM(splitFlowMotions(c, scene.camera, cfg).T_b_a_background, T_b_a * boxMotion()), 1e-3);
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
  const FlowMotionSplit split = splitFlowMotions(c, scene.camera, ConsensusConfig{});
  ASSERT_TRUE(split.ok);
  const SE3 T_b_a = T_world_b.inverse();
  // 5.2 mm with DIS medium (the default preset), under 5 mm with fast.
  EXPECT_LT(translationErrorM(split.T_b_a_background, T_b_a), 6e-3);
  EXPECT_LT(rotationAngleDeg(split.T_b_a_background.inverse() * T_b_a), 0.2);
}

// A wall 2 m away seen by a camera turning `turn_deg` about its y axis, a fifth of the samples (a
// band of rows) moved by `extra_deg` more, split by hand into those two motions: the separation
// share is the extra turn over the turn (the image motion of a turn is nearly uniform).
struct TurningSplit {
  CameraIntrinsics camera{517.3, 516.5, 318.6, 255.3, 640, 480};
  FlowCorrespondences c;
  FlowMotionSplit split;
  TurningSplit(double turn_deg, double extra_deg) {
    const auto turn = [](double deg) { return SE3(Eigen::AngleAxisd(deg * M_PI / 180, Eigen::Vector3d::UnitY())); };
    split.ok = true;
    split.T_b_a_background = turn(turn_deg);
    split.T_b_a_mover = turn(turn_deg + extra_deg);
    for (int v = 8; v < camera.height; v += 16)
      for (int u = 8; u < camera.width; u += 16) {
        const Eigen::Vector3d X = camera.backproject(u, v, 2.0);
        const bool mover = v < camera.height / 5;
        const Eigen::Vector2d b = camera.project((mover ? split.T_b_a_mover : split.T_b_a_background) * X);
        c.points_a.emplace_back(X.x(), X.y(), X.z());
        c.pixels_b.emplace_back(b.x(), b.y());
        split.group.push_back(mover ? FlowMotionSplit::kMover : FlowMotionSplit::kBackground);
      }
  }
};

TEST(FlowMotion, AStartMoverGroupMustLieApartBeyondTheFlowsErrorAtThatImageMotion) {
  const ConsensusConfig cfg;  // start_min_separation 0.15
  // Turning 3 degrees a frame (27 px of flow), a second motion 0.25 degrees off: 8 %, flow error.
  const TurningSplit fast(3.0, 0.25);
  EXPECT_NEAR(moverSeparationShare(fast.split, fast.c, fast.camera), 0.25 / 3.0, 0.01);
  EXPECT_FALSE(showsMoverGroup(fast.split, fast.c, fast.camera, cfg));
  // The same 0.25 degrees while the camera turns 0.5 degrees a frame: half the image motion, a mover.
  const TurningSplit slow(0.5, 0.25);
  EXPECT_NEAR(moverSeparationShare(slow.split, slow.c, slow.camera), 0.5, 0.05);
  EXPECT_TRUE(showsMoverGroup(slow.split, slow.c, slow.camera, cfg));
  // A still camera: any separate motion is apart from it.
  const TurningSplit still(0.0, 0.25);
  EXPECT_TRUE(std::isinf(moverSeparationShare(still.split, still.c, still.camera)));
  ConsensusConfig any = cfg;
  any.start_min_separation = 0;
  EXPECT_TRUE(showsMoverGroup(fast.split, fast.c, fast.camera, any));
}

// A slowly turning camera's mover group (the band of rows of TurningSplit, v < 96) whose samples lie
// on a black screen over the columns left of `black_until_u`, grey elsewhere: the black share is
// the share of its columns (the samples lie every 16 px from u = 8), the frame's a fifth of that.
TEST(FlowMotion, AStartMoverGroupMostlyOnBlackPixelsIsNoMover) {
  const ConsensusConfig cfg;  // start_max_black_share 0.6
  const TurningSplit slow(0.5, 0.25);
  const auto intensity = [&](int black_until_u) {
    cv::Mat grey(slow.camera.height, slow.camera.width, CV_32F, cv::Scalar(0.5));
    grey(cv::Rect(0, 0, black_until_u, slow.camera.height / 5)).setTo(0.02);
    return grey;
  };
  const cv::Mat screen = intensity(448), corner = intensity(256);  // 28 and 16 of the 40 columns
  EXPECT_NEAR(samplesShareWhere(slow.c, slow.camera, screen < kBlackGrey, &slow.split), 0.7, 1e-9);
  EXPECT_NEAR(samplesShareWhere(slow.c, slow.camera, screen < kBlackGrey), 0.7 / 5, 1e-9);
  EXPECT_NEAR(samplesShareWhere(slow.c, slow.camera, corner < kBlackGrey, &slow.split), 0.4, 1e-9);
  EXPECT_FALSE(showsMoverGroup(slow.split, slow.c, slow.camera, cfg, screen));
  EXPECT_TRUE(showsMoverGroup(slow.split, slow.c, slow.camera, cfg, corner));
  EXPECT_TRUE(showsMoverGroup(slow.split, slow.c, slow.camera, cfg));  // no image: not tested
  ConsensusConfig any = cfg;
  any.start_max_black_share = 1;
  EXPECT_TRUE(showsMoverGroup(slow.split, slow.c, slow.camera, any, screen));
  // A dim room, every sample black: black says nothing of a screen there.
  const cv::Mat dim(slow.camera.height, slow.camera.width, CV_32F, cv::Scalar(0.05));
  EXPECT_TRUE(showsMoverGroup(slow.split, slow.c, slow.camera, cfg, dim));
  EXPECT_THROW(samplesShareWhere(slow.c, slow.camera, cv::Mat(10, 10, CV_8U, cv::Scalar(0))), InputError);
}

TEST(FlowMotion, TooFewSamplesGiveNoSplit) {
  const AnalyticScene scene = AnalyticScene::make(320, 240);
  const auto a = scene.render(SE3::Identity());
  cv::Mat sparse_depth(a.frame.depth.size(), CV_32F, cv::Scalar(0));
  a.frame.depth(cv::Rect(100, 100, 20, 20)).copyTo(sparse_depth(cv::Rect(100, 100, 20, 20)));
  const FlowField flow{egoFlow(a.frame.depth, scene.camera, cameraMotion())};
  const FlowCorrespondences c = sampleFlowCorrespondences(flow, sparse_depth, scene.camera, 16);
  EXPECT_LT(c.size(), 30u);
  EXPECT_FALSE(splitFlowMotions(c, scene.camera, ConsensusConfig{}).ok);
}

TEST(FlowMotion, SamplingRejectsMismatchedInputsAndBadConfigs) {
  const AnalyticScene scene = AnalyticScene::make(320, 240);
  const cv::Mat depth(240, 320, CV_32F, cv::Scalar(1));
  const FlowField small{cv::Mat(120, 160, CV_32FC2, cv::Scalar(0, 0))};
  EXPECT_THROW(sampleFlowCorrespondences(small, depth, scene.camera, 8), InputError);
  const FlowField still{cv::Mat(240, 320, CV_32FC2, cv::Scalar(0, 0))};
  const cv::Mat half_intensity(120, 160, CV_32F, cv::Scalar(0.5));
  EXPECT_THROW(sampleFlowCorrespondences(still, depth, scene.camera, 8, half_intensity, 0.8), InputError);
  ConsensusConfig bad;
  bad.inlier_px = 0;
  EXPECT_THROW(validate(bad), InputError);
  bad = ConsensusConfig{};
  bad.min_mover_share = 1.5;
  EXPECT_THROW(validate(bad), InputError);
  bad = ConsensusConfig{};
  bad.start_min_separation = -0.1;
  EXPECT_THROW(validate(bad), InputError);
  bad = ConsensusConfig{};
  bad.start_max_black_share = 1.5;
  EXPECT_THROW(validate(bad), InputError);
  bad = ConsensusConfig{};
  bad.start_min_texture = -1;
  EXPECT_THROW(validate(bad), InputError);
  bad = ConsensusConfig{};
  bad.min_captured = 0;
  EXPECT_THROW(validate(bad), InputError);
  bad = ConsensusConfig{};
  bad.grid_step = 0;
  EXPECT_THROW(validate(bad), InputError);
  bad = ConsensusConfig{};
  bad.map_role_margin = 0;
  EXPECT_THROW(validate(bad), InputError);
  bad = ConsensusConfig{};
  bad.nearer_mover_depth_ratio = 1;
  EXPECT_THROW(validate(bad), InputError);
}

}  // namespace
}  // namespace ff
