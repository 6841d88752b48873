// The tracking-target policy on its own: which frame serves as the target, when a keyframe is
// replaced, what weights a target carries, and the map's prediction as a target.
#include <gtest/gtest.h>

#include <optional>

#include "flowfusion/pipeline/tracking_target.h"
#include "flowfusion/synth/synthetic_scene.h"

namespace ff {
namespace {

class TrackingTargetsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    synth::SynthConfig c;
    c.frames = 12;
    c.width = 160;
    c.height = 120;
    c.objects = 0;
    scene_ = std::make_unique<synth::SyntheticScene>(c);
  }
  // Frame i at pose T (exact poses unless given).
  TrackedFrame tracked(int i, std::optional<SE3> T = std::nullopt) const {
    const auto f = scene_->render(i);
    return {f.frame, prepareOdometryFrame(f.frame.intensity, f.frame.depth, scene_->camera(), odometry_),
            T ? *T : f.T_world_cam, cv::Mat(), cv::Mat(), false};
  }
  OdometryConfig odometry_;
  Timings timings_;
  std::unique_ptr<synth::SyntheticScene> scene_;
};

TEST_F(TrackingTargetsTest, FrameToFrameAlwaysTargetsThePreviousFrame) {
  PipelineOptions p;
  p.tracking = TrackingMode::FrameToFrame;
  TrackingTargets targets(p, odometry_, scene_->camera());
  EXPECT_EQ(targets.previous(), nullptr);
  for (int i = 0; i < 3; ++i) {
    targets.advance(tracked(i), true, {}, nullptr, timings_);
    const TrackingTarget t = targets.choose(nullptr, timings_);
    EXPECT_EQ(t.odo, &targets.previous()->odo);
    EXPECT_TRUE(t.T_world_target.isApprox(scene_->cameraPose(i)));
    EXPECT_FALSE(t.from_model);
  }
}

TEST_F(TrackingTargetsTest, AKeyframeStaysUntilTheCameraMovesFarEnough) {
  PipelineOptions p;
  p.keyframe_translation = 0.05;
  p.model_keyframes = false;
  TrackingTargets targets(p, odometry_, scene_->camera());
  const SE3 start = scene_->cameraPose(0);
  SE3 step = SE3::Identity();
  step.translation() = Eigen::Vector3d(0.02, 0, 0);  // 2 cm per frame
  SE3 T = start;
  targets.advance(tracked(0, T), true, {}, nullptr, timings_);
  for (int i = 1; i <= 2; ++i) {
    T = T * step;
    targets.advance(tracked(i, T), true, {}, nullptr, timings_);
    EXPECT_TRUE(targets.choose(nullptr, timings_).T_world_target.isApprox(start)) << "frame " << i << ": 2-4 cm";
  }
  T = T * step;  // 6 cm from the keyframe: this frame becomes the keyframe
  targets.advance(tracked(3, T), true, {}, nullptr, timings_);
  EXPECT_TRUE(targets.choose(nullptr, timings_).T_world_target.isApprox(T));
  // A frame whose tracking failed is always a new keyframe.
  targets.advance(tracked(4, T), false, {}, nullptr, timings_);
  EXPECT_EQ(targets.choose(nullptr, timings_).odo->level(1).intensity.data,
            targets.previous()->odo.level(1).intensity.data);
}

TEST_F(TrackingTargetsTest, TheFirstScoredFrameReplacesAKeyframeWithoutScores) {
  // The first frame has no scores: its moving objects would pull every frame aligned to it. All
  // frames here stand at the first pose, so only the scores make a keyframe; each frame's target
  // weights hold its index, which tells the keyframe.
  const SE3 T = scene_->cameraPose(0);
  auto frame = [&](int i, bool with_scores) {
    TrackedFrame f = tracked(i, T);
    f.target_weights = cv::Mat(60, 80, CV_32F, cv::Scalar(static_cast<float>(i)));
    if (with_scores) f.scores = cv::Mat(60, 80, CV_32F, cv::Scalar(0.f));
    return f;
  };
  auto keyframe = [&](const TrackingTargets& t) { return t.choose(nullptr, timings_).weights->at<float>(0, 0); };
  PipelineOptions p;
  p.model_keyframes = false;
  TrackingTargets targets(p, odometry_, scene_->camera());
  targets.advance(frame(0, false), true, {}, nullptr, timings_);
  targets.advance(frame(1, true), true, {}, nullptr, timings_);
  EXPECT_EQ(keyframe(targets), 1.f);
  // A scored keyframe stays while the camera is near it.
  targets.advance(frame(2, true), true, {}, nullptr, timings_);
  EXPECT_EQ(keyframe(targets), 1.f);
  // Without segmentation no frame has scores, and the first frame stays the keyframe.
  TrackingTargets plain(p, odometry_, scene_->camera());
  for (int i = 0; i < 3; ++i) plain.advance(frame(i, false), true, {}, nullptr, timings_);
  EXPECT_EQ(keyframe(plain), 0.f);
  // With model keyframes the map is rendered for the first scored frame.
  TrackingTargets with_model(PipelineOptions{}, odometry_, scene_->camera());
  with_model.advance(frame(0, false), true, {}, nullptr, timings_);
  EXPECT_TRUE(with_model.rendersOnAdvance(T, true, true));
  EXPECT_FALSE(with_model.rendersOnAdvance(T, true, false));
}

TEST_F(TrackingTargetsTest, TargetsCarryTheirStaticWeights) {
  PipelineOptions p;
  p.model_keyframes = false;
  TrackingTargets targets(p, odometry_, scene_->camera());
  TrackedFrame f = tracked(0);
  f.target_weights = cv::Mat(60, 80, CV_32F, cv::Scalar(0.25f));
  targets.advance(std::move(f), true, {}, nullptr, timings_);
  const TrackingTarget t = targets.choose(nullptr, timings_);
  ASSERT_FALSE(t.weights->empty());
  EXPECT_FLOAT_EQ(t.weights->at<float>(10, 10), 0.25f);
}

TEST_F(TrackingTargetsTest, ModelKeyframesAndFrameToModelRenderTheMap) {
  StaticMap map;
  for (int i = 0; i < 6; ++i) {
    const auto f = scene_->render(i);
    map.integrate(f.frame, scene_->camera(), f.T_world_cam);
  }
  PipelineOptions keyframes;
  TrackingTargets with_keyframes(keyframes, odometry_, scene_->camera());
  with_keyframes.advance(tracked(6), true, {}, &map, timings_);
  const TrackingTarget k = with_keyframes.choose(&map, timings_);
  EXPECT_TRUE(k.from_model);
  // The rendered depth agrees with the frame's own where both exist (exact synthetic geometry).
  const cv::Mat& rendered = k.odo->level(1).depth;
  const cv::Mat& own = with_keyframes.previous()->odo.level(1).depth;
  cv::Mat both = (rendered > 0) & (own > 0);
  cv::Mat diff;
  cv::absdiff(rendered, own, diff);
  EXPECT_GT(cv::countNonZero(both), static_cast<int>(both.total() / 2));
  EXPECT_LT(cv::mean(diff, both)[0], 0.02);

  // A static surface the map does not hold yet (a square 1 m in front of the camera) stays in the
  // keyframe with the frame's own depth; the map's depth everywhere else.
  TrackedFrame with_new_surface = tracked(6);
  cv::Mat near_depth = scene_->render(6).frame.depth.clone();
  near_depth(cv::Rect(40, 30, 20, 20)).setTo(1.0f);
  with_new_surface.frame.depth = near_depth;
  with_new_surface.odo =
      prepareOdometryFrame(with_new_surface.frame.intensity, near_depth, scene_->camera(), odometry_);
  TrackingTargets new_surface(keyframes, odometry_, scene_->camera());
  new_surface.advance(std::move(with_new_surface), true, {}, &map, timings_);
  const TrackingTarget n = new_surface.choose(&map, timings_);
  ASSERT_TRUE(n.from_model);
  EXPECT_FLOAT_EQ(n.odo->level(1).depth.at<float>(20, 25), 1.0f);  // level 1: half size
  EXPECT_FLOAT_EQ(n.odo->level(1).depth.at<float>(50, 60), rendered.at<float>(50, 60));

  PipelineOptions model;
  model.tracking = TrackingMode::FrameToModel;
  TrackingTargets to_model(model, odometry_, scene_->camera());
  to_model.advance(tracked(6), true, {}, &map, timings_);
  const TrackingTarget m = to_model.choose(&map, timings_);
  EXPECT_TRUE(m.from_model);
  EXPECT_TRUE(m.weights->empty()) << "a rendered target has no moving objects";
  EXPECT_FALSE(to_model.previousFrame().from_model);
  StaticMap empty;
  EXPECT_FALSE(to_model.choose(&empty, timings_).from_model) << "an empty map falls back to the previous frame";
}

}  // namespace
}  // namespace ff
