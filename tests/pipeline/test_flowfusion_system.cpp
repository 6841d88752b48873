// End-to-end checks of FlowFusionSystem on synthetic sequences with exact ground truth (poses and
// dynamic masks): a static room must stay static and be tracked well, moving objects must be
// segmented and must not spoil the trajectory.
//
// Small images (320x240) and 40 frames keep the file within CI's budget (2 cores).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <optional>
#include <vector>

#include "flowfusion/core/error.h"
#include "flowfusion/eval/trajectory_metrics.h"
#include "flowfusion/io/tum_sequence.h"
#include "flowfusion/pipeline/flowfusion_system.h"
#include "flowfusion/synth/synthetic_scene.h"
#include "testing/test_util.h"

namespace ff {
namespace {

namespace fs = std::filesystem;

// Seed 2: both objects are in view from the first frame on and cover 6-12 % of the image over the
// first 40 frames (with seed 1 they enter only at frame ~54).
synth::SynthConfig smallScene(int objects, uint64_t seed = 2) {
  synth::SynthConfig c;
  c.seed = seed;
  c.frames = 40;
  c.objects = objects;
  c.width = 320;
  c.height = 240;
  return c;
}

struct RunResult {
  double ate_rmse_m = 0;
  double dynamic_fraction = 0;   // dynamic pixels over all pixels of all frames
  double mean_iou = 0;           // over frames where a moving object covers >= 1 % of the image
  int iou_frames = 0;
  int model_frames = 0;          // frames aligned to the map's prediction
  int flow_restarts = 0;
};

double iou(const cv::Mat& gt, const cv::Mat& est) {
  const int inter = cv::countNonZero(gt & est);
  const int uni = cv::countNonZero(gt | est);
  return uni == 0 ? 1.0 : static_cast<double>(inter) / uni;
}

RunResult runOn(const synth::SyntheticScene& scene, const SystemConfig& config) {
  FlowFusionSystem system(config, scene.camera(), scene.cameraPose(0));
  Trajectory gt;
  RunResult out;
  double dynamic_pixels = 0, pixels = 0, iou_sum = 0;
  for (int i = 0; i < scene.frameCount(); ++i) {
    const synth::SynthFrame f = scene.render(i);
    gt.push_back({scene.timestamp(i), f.T_world_cam});
    const FrameResult r = system.process(f.frame);
    EXPECT_EQ(r.dynamic_mask.size(), f.mask.size());
    dynamic_pixels += cv::countNonZero(r.dynamic_mask);
    out.model_frames += r.used_model ? 1 : 0;
    pixels += static_cast<double>(f.mask.total());
    // Frame 0 has no previous frame to compare with, so nothing can be segmented there.
    if (i > 0 && cv::countNonZero(f.mask) >= 0.01 * static_cast<double>(f.mask.total())) {
      iou_sum += iou(f.mask, r.dynamic_mask);
      ++out.iou_frames;
    }
  }
  out.ate_rmse_m = eval::computeAte(gt, system.trajectory()).translation_m.rmse;
  out.flow_restarts = system.flowRestarts();
  out.dynamic_fraction = dynamic_pixels / pixels;
  out.mean_iou = out.iou_frames > 0 ? iou_sum / out.iou_frames : 0;
  return out;
}

RunResult runOn(const synth::SyntheticScene& scene, bool segmentation,
                std::optional<TrackingMode> tracking = std::nullopt) {
  SystemConfig config;
  config.pipeline.segmentation = segmentation;
  if (tracking) config.pipeline.tracking = *tracking;
  return runOn(scene, config);
}

// Each scene is rendered and run once for all tests below.
const RunResult& staticRun() {
  static const RunResult r = runOn(synth::SyntheticScene(smallScene(0)), true);
  return r;
}
const RunResult& dynamicRun() {
  static const RunResult r = runOn(synth::SyntheticScene(smallScene(2)), true);
  return r;
}
const RunResult& dynamicRunNoSegmentation() {
  static const RunResult r = runOn(synth::SyntheticScene(smallScene(2)), false);
  return r;
}

TEST(FlowFusionSystem, FrameToModelTracksAgainstTheMap) {
  const RunResult r = runOn(synth::SyntheticScene(smallScene(0)), true, TrackingMode::FrameToModel);
  std::cout << "frame to model: " << r.model_frames << " of 39 frames aligned to the map, ATE "
            << 1e3 * r.ate_rmse_m << " mm\n";
  // Measured: 39 of 39, ATE 1.6 mm (9.4 mm when the prediction kept the nearest disc intersection
  // per pixel: noisy discs tilted towards the camera biased the model's depth by -12 mm).
  EXPECT_GE(r.model_frames, 30);
  EXPECT_LT(r.ate_rmse_m, 0.005);
}

TEST(FlowFusionSystem, KeyframesAreTheMapsPrediction) {
  const RunResult& r = staticRun();
  std::cout << "model keyframes: " << r.model_frames << " of 39 frames aligned to one\n";
  // Measured: 39 of 39 (frame 0 is fused before it becomes the first keyframe).
  EXPECT_GE(r.model_frames, 30);
}

TEST(FlowFusionSystem, StaticSceneStaysStaticAndIsTrackedWell) {
  const RunResult& r = staticRun();
  // Measured (bdea860 defaults): 0.00 % of the pixels dynamic, ATE 0.9 mm.
  EXPECT_LT(r.dynamic_fraction, 0.02);
  EXPECT_LT(r.ate_rmse_m, 0.005);
}

TEST(FlowFusionSystem, MovingObjectsAreSegmented) {
  const RunResult& r = dynamicRun();
  std::cout << "dynamic scene: mean IoU " << r.mean_iou << " over " << r.iou_frames << " frames\n";
  ASSERT_GT(r.iou_frames, 10) << "the scene should show its objects in most frames";
  // Measured: mean IoU 0.76 over 39 frames (0.74 before OdometryConfig::occlusion_ratio, 0.107
  // before the static-model term of ScoreConfig, 0.70 before the target weights and the
  // map-agreement evidence). The objects are in view from frame 0, so the map starts with them and
  // their first frames are only found by their moving edges.
  EXPECT_GE(r.mean_iou, 0.75);
}

TEST(FlowFusionSystem, MovingObjectsDoNotSpoilTheTrajectory) {
  const RunResult& dyn = dynamicRun();
  const RunResult& off = dynamicRunNoSegmentation();
  const RunResult& stat = staticRun();
  std::cout << "ATE mm: dynamic " << 1e3 * dyn.ate_rmse_m << ", without segmentation " << 1e3 * off.ate_rmse_m
            << ", static twin " << 1e3 * stat.ate_rmse_m << "\n";
  // Measured: ATE 0.99 mm with segmentation (5.6 mm before the flow residual's consistency check
  // and error field, 66.8 mm before the static-model term, 6.8 mm before the target weights), static
  // twin 0.99 mm: the issue-4 target (dynamic <= 1.25x static) is met on this small scene, whose
  // objects are in view from the first frame.
  EXPECT_LT(dyn.ate_rmse_m, 0.01);
  EXPECT_LT(dyn.ate_rmse_m, 1.25 * stat.ate_rmse_m);
}

TEST(FlowFusionSystem, ALargeObjectMovingFromTheFirstFrameDoesNotCaptureTheOdometry) {
  // Seed 3 at full size: a near box covering a quarter of the view slides across from frame 0,
  // before any score exists; the plain robust odometry follows it and the carried scores then
  // call the background dynamic (the full 150 frames: 117 mm ATE without the flow consensus).
  synth::SynthConfig c = smallScene(2, 3);
  c.frames = 12;
  c.width = 640;
  c.height = 480;
  const synth::SyntheticScene scene(c);
  SystemConfig with;
  SystemConfig without;
  without.consensus.enabled = false;
  // The cause is shown with the flow residual of then (DIS fast, no consistency check, no error
  // field): with them the segmentation alone keeps this box out (7.5 mm without the consensus).
  without.flow.dis_preset = DisPreset::Fast;
  without.scores.flow_consistency_px = 0;
  without.scores.flow_error_field = FlowErrorField::kNone;
  const RunResult on = runOn(scene, with), off = runOn(scene, without);
  std::cout << "ATE mm: flow consensus " << 1e3 * on.ate_rmse_m << " (" << on.flow_restarts << " restarts), without "
            << 1e3 * off.ate_rmse_m << "\n";
  // Measured: 14.9 mm (11.3 mm with the flow of then) with 3 restarts, 61 mm without (8.3 and 62 mm
  // with plain keyframes).
  EXPECT_GE(on.flow_restarts, 1);
  EXPECT_LT(on.ate_rmse_m, 0.02);
  EXPECT_GT(off.ate_rmse_m, 2 * on.ate_rmse_m);
}

TEST(SystemConfig, BadSettingsAreRejectedByName) {
  auto rejects = [](auto&& edit, const std::string& name) {
    SystemConfig c;
    edit(c);
    try {
      validate(c);
      ADD_FAILURE() << name << " was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  };
  rejects([](SystemConfig& c) { c.pipeline.tracking = TrackingMode::FrameToModel, c.pipeline.fusion = false; },
          "pipeline.tracking");
  rejects([](SystemConfig& c) { c.scores.theta_t = c.scores.theta_b; }, "scores.theta_t");
  rejects([](SystemConfig& c) { c.scores.alpha_M = -1; }, "scores.alpha_M");
  rejects([](SystemConfig& c) { c.scores.group_depth_ratio = 1; }, "scores.group_depth_ratio");
  rejects([](SystemConfig& c) { c.scores.model_margin = -0.1; }, "scores.model_margin");
  rejects([](SystemConfig& c) { c.scores.model_agreement = 1.5; }, "scores.model_agreement");
  rejects([](SystemConfig& c) { c.scores.agreement_margin = 0; }, "scores.agreement_margin");
  rejects([](SystemConfig& c) { c.scores.long_baseline_noise_px = -0.5; }, "scores.long_baseline_noise_px");
  rejects([](SystemConfig& c) { c.scores.long_baseline_noise_px = std::nan(""); }, "scores.long_baseline_noise_px");
  rejects([](SystemConfig& c) { c.pipeline.refine_coarsest_level = 9; }, "pipeline.refine_coarsest_level");
  rejects([](SystemConfig& c) { c.pipeline.refine_iterations = 0; }, "pipeline.refine_iterations");
  rejects([](SystemConfig& c) { c.pipeline.fusion_every = 0; }, "pipeline.fusion_every");
  rejects([](SystemConfig& c) { c.consensus.ransac_iterations = 0; }, "consensus.ransac_iterations");
  EXPECT_NO_THROW(validate(SystemConfig{}));
  nlohmann::json j = SystemConfig{};
  j["pipeline"]["tracking"] = "icp";
  try {
    j.get<SystemConfig>();
    ADD_FAILURE() << "pipeline.tracking icp was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("frame_to_frame, frame_to_keyframe or frame_to_model"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace ff
