#include "flowfusion/pipeline/flowfusion_system.h"

#include <chrono>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <utility>

#include "flowfusion/core/error.h"
#include "flowfusion/segmentation/depth_holes.h"
#include "flowfusion/segmentation/dynamic_score.h"
#include "flowfusion/segmentation/map_agreement_mask.h"
#include "flowfusion/segmentation/mask_edges.h"
#include "flowfusion/segmentation/score_carry.h"
#include "flowfusion/segmentation/small_regions.h"

namespace ff {

namespace {

using Clock = std::chrono::steady_clock;

// The frame found in a saved map is aligned to the map's rendering at its pose until a step moves
// it by less than this, at most kMaxMapRefinements times (each a rendering and an odometry). On the
// test's room, 1, 2, 4 alignments: 7.9 cm off the truth -> 1.8, 1.3 cm (test_map_reuse.cpp).
constexpr int kMaxMapRefinements = 5;
constexpr double kMapRefinedStepM = 0.001, kMapRefinedStepDeg = 0.1;

const SystemConfig& validated(const SystemConfig& config) {
  validate(config);
  return config;
}

}  // namespace

FlowFusionSystem::FlowFusionSystem(const SystemConfig& config, const CameraIntrinsics& camera, const SE3& T_world_first,
                                   const SavedMap* map_in)
    : config_(validated(config)),
      camera_(camera),
      odometry_(config.odometry),
      targets_(config.pipeline, config.odometry, camera),
      T_world_first_(T_world_first),
      frames_since_fusion_(config_.pipeline.fusion_every) {
  if (config_.pipeline.segmentation) segmentation_ = std::make_unique<SegmentationLoop>(config_, camera_);
  if (config_.pipeline.fusion) map_ = std::make_unique<StaticMap>(config_.fusion);
  slam_ = makeSlamBackEnd(config_.slam, config_.odometry, camera_, &slam_note_);
  if (map_in) continueIn(*map_in);
}

void FlowFusionSystem::continueIn(const SavedMap& map) {
  if (!slam_)
    throw InputError(map.path + ": continuing in a saved map needs loop closure (slam.loop_closure ferns" +
                     (slam_note_.empty() ? std::string() : "; " + slam_note_) + ")");
  checkMapFits(map, camera_, config_.slam);
  slam_->loadKeyframes(map.keyframes);
  if (map_) map_->loadSurfels(map.surfels);
  map_reuse_ = MapReuse{map.path, static_cast<int>(map.keyframes.size()), map.surfels.size()};
}

SE3 FlowFusionSystem::refinedInSavedMap(const OdometryFrame& cur, const SE3& T_world_cam) const {
  if (!map_) return T_world_cam;
  SE3 T = T_world_cam;
  for (int i = 0; i < kMaxMapRefinements; ++i) {
    const ModelPrediction p = map_->predict(T, camera_);
    const OdometryFrame target = prepareOdometryFrame(p.intensity, p.depth, camera_, config_.odometry);
    const OdometryResult r = odometry_.estimate(cur, target, SE3::Identity(), {}, {});
    if (!r.ok) break;
    T = orthonormalized(T * r.T_target_source);
    if (translationNorm(r.T_target_source) < kMapRefinedStepM && rotationAngleDeg(r.T_target_source) < kMapRefinedStepDeg)
      break;
  }
  return T;
}

bool FlowFusionSystem::localizeInSavedMap(const RgbdFrame& frame, const OdometryFrame& cur, FrameResult& result) {
  StageTimer timer(timings_, "relocalization");
  const std::optional<SE3> found = slam_->relocalize(frame, {});
  if (!found) {
    ++map_reuse_->unlocalized_frames;
    result.tracking_ok = result.has_pose = false;
    result.message = "not localized in the saved map yet: no keyframe matches";
    return false;
  }
  map_reuse_->localized_at_frame = static_cast<int>(frame_ms_.size());
  T_world_first_ = refinedInSavedMap(cur, *found);
  return true;
}

OdometryFrame FlowFusionSystem::prepare(const RgbdFrame& frame) {
  if (frame.width() != camera_.width || frame.height() != camera_.height)
    throw InputError(frame.name + ": frame is " + std::to_string(frame.width()) + "x" +
                     std::to_string(frame.height()) + ", the camera is " + std::to_string(camera_.width) + "x" +
                     std::to_string(camera_.height));
  StageTimer timer(timings_, "odometry");
  return prepareOdometryFrame(frame.intensity, frame.depth, camera_, config_.odometry);
}

const StaticMap* FlowFusionSystem::map() const {
  finishFusion();
  return map_.get();
}

Timings& FlowFusionSystem::timings() {
  finishFusion();
  return timings_;
}

const Timings& FlowFusionSystem::timings() const {
  finishFusion();
  return timings_;
}

FrameResult FlowFusionSystem::process(const RgbdFrame& frame) {
  const Clock::time_point start = Clock::now();
  if (config_.pipeline.budget_ms > 0)
    deadline_ = start + std::chrono::duration_cast<Clock::duration>(
                            std::chrono::duration<double, std::milli>(config_.pipeline.budget_ms));
  FrameResult result;
  result.timestamp = frame.timestamp;
  timings_.beginFrame(frame.timestamp);
  applyLoopCorrections();
  OdometryFrame cur = prepare(frame);
  if (map_reuse_ && map_reuse_->localized_at_frame < 0 && !localizeInSavedMap(frame, cur, result)) {
    result.dynamic_mask = cv::Mat(frame.depth.size(), CV_8U, cv::Scalar(0));
    frame_ms_.push_back(msSince(start));
    return result;
  }
  TrackedScores tracked;
  if (!targets_.previous()) {
    result.T_world_cam = T_world_first_;
    result.message = map_reuse_ ? "localized in the saved map" : "first frame";
  } else {
    tracked = track(frame, cur, result);
    if (!result.tracking_ok && slam_) relocalize(frame, result, tracked.scores);
  }
  const cv::Mat& scores = tracked.scores;  // b per pixel at the segmentation level
  cv::Mat full_scores;
  if (!scores.empty()) cv::resize(scores, full_scores, frame.depth.size(), 0, 0, cv::INTER_NEAREST);
  result.dynamic_mask = full_scores.empty() ? cv::Mat(frame.depth.size(), CV_8U, cv::Scalar(0))
                                            : dynamicMask(full_scores, config_.pipeline.mask_threshold);
  result.scores = scores;
  result.clusters = std::move(tracked.clusters);
  // A frame whose tracking failed stays out of the map when loop closure can find it again.
  const bool fused =
      (result.tracking_ok || !slam_) && startFusion(frame, result.T_world_cam, full_scores, Clock::now() > deadline_);
  // A new model keyframe is the map rendered at this frame's pose, this frame's fusion included.
  if (targets_.rendersOnAdvance(result.T_world_cam, result.tracking_ok, !scores.empty())) finishFusion();
  // As a target (the next frame's previous frame or keyframe), this frame's moving pixels count less.
  targets_.advance({frame, std::move(cur), result.T_world_cam, scores, staticWeights(scores)}, result.tracking_ok,
                   result.dynamic_mask, map_.get(), timings_);
  if (!full_scores.empty()) finishWrittenMask(frame, tracked, result.dynamic_mask);
  trajectory_.push_back({frame.timestamp, atColourTime(frame, result.T_world_cam)});
  if (slam_) {
    StageTimer timer(timings_, "loop_closure");
    slam_->frameTracked({&frame, result.T_world_cam, trajectory_.back().T_world_cam, result.tracking_ok, scores, fused});
  }
  frame_ms_.push_back(msSince(start));
  return result;
}

void FlowFusionSystem::finishWrittenMask(const RgbdFrame& frame, const TrackedScores& tracked, cv::Mat& mask) const {
  // Only the written mask: the tracking and the map have used the scores, and pixels without depth
  // are nothing either can use.
  const PipelineOptions& opt = config_.pipeline;
  // A segmentation-level image at the mask's size, pixel for pixel (empty stays empty).
  const auto atMaskSize = [&mask](const cv::Mat& level_image) {
    cv::Mat out;
    if (!level_image.empty()) cv::resize(level_image, out, mask.size(), 0, 0, cv::INTER_NEAREST);
    return out;
  };
  if (opt.mask_map_agreement) clearMapAgreement(mask, tracked.map_agreement);
  dropSmallInteriorRegions(mask, opt.mask_min_region, atMaskSize(tracked.seen_moving));
  if (opt.mask_hole_share > 0) fillDepthHoles(mask, frame.depth, opt.mask_hole_share, atMaskSize(tracked.sensor_band));
  cv::Mat moving = atMaskSize(tracked.moving_holes);
  if (!moving.empty()) moving.setTo(0, frame.depth > 0.f);  // the input's own holes within the level's
  if (opt.mask_band_holes) {
    const cv::Mat band = atMaskSize(tracked.sensor_band);
    if (opt.mask_band_reach_px > 0) {
      const cv::Mat beside = bandBesideMovers(band, mask, frame.depth, opt.mask_band_reach_px);
      if (cv::countNonZero(beside) > 0) moving = moving.empty() ? beside : (moving | beside);
    }
    if (!moving.empty()) clearBandHolesOfWorldColour(moving, band, mask, frame.color, frame.depth);
  }
  if (!moving.empty()) markHolesBesideMovers(mask, moving);
  refineMaskEdges(mask, frame.depth, frame.color, opt.mask_edge_px);
}

FlowFusionSystem::TrackedScores FlowFusionSystem::track(const RgbdFrame& frame, const OdometryFrame& cur,
                                                        FrameResult& result) {
  const PipelineOptions& opt = config_.pipeline;
  const TrackedFrame& prev = *targets_.previous();
  if (opt.tracking == TrackingMode::FrameToModel) finishFusion();  // choose() renders the map
  TrackingTarget target = targets_.choose(map_.get(), timings_);
  SE3 T_target_prev = target.T_world_target.inverse() * prev.T_world_cam;
  const SE3 T_prev_cur_guess = opt.constant_velocity ? T_prev_cur_velocity_ : SE3::Identity();
  cv::Mat carried;
  if (segmentation_ && opt.carry_scores && !prev.scores.empty())
    carried = carryScores(prev.scores, prev.depthAt(opt.segmentation_level),
                          camera_.atLevel(opt.segmentation_level), T_prev_cur_guess.inverse(), 0.f);
  // The flow and the clusters need neither the odometry nor the map: they run beside the first odometry.
  std::future<FrameCues> cues_task;
  if (segmentation_)
    cues_task = std::async(std::launch::async, [this, &frame, &cur, &prev] {
      return segmentation_->computeCues(frame, cur, prev.frame);
    });
  MotionEstimate estimate = firstOdometry(cur, target, T_target_prev, T_prev_cur_guess, carried, result);
  if (segmentation_) {
    const FrameCues cues = cues_task.get();
    timings_.add("flow", cues.flow_ms);
    timings_.add("clustering", cues.clustering_ms);
    finishFusion();  // the loop reads the map
    segmentation_->run({frame, cur, prev, target, T_target_prev, map_.get(), deadline_}, cues, estimate, timings_);
    result.restarted_from_flow = estimate.restarted_from_flow;
    result.iterations = estimate.rounds;
    flow_restarts_ += estimate.restarted_from_flow;
  }
  if (!estimate.odometry.ok) {
    ++failures_;
    result.tracking_ok = false;
    result.message = estimate.odometry.message + "; kept the constant-velocity guess";
  }
  result.T_world_cam = orthonormalized(target.T_world_target * estimate.T_target_cur);
  T_prev_cur_velocity_ = prev.T_world_cam.inverse() * result.T_world_cam;
  velocity_dt_ = frame.depthTime() - prev.frame.depthTime();
  return {estimate.scores, estimate.map_agreement, estimate.seen_moving, estimate.moving_holes, estimate.sensor_band,
          std::move(estimate.cluster_log)};
}

MotionEstimate FlowFusionSystem::firstOdometry(const OdometryFrame& cur, TrackingTarget& target, SE3& T_target_prev,
                                               const SE3& T_prev_cur_guess, const cv::Mat& carried,
                                               FrameResult& result) {
  StageTimer timer(timings_, "odometry");
  const cv::Mat weights = staticWeights(carried);
  MotionEstimate e;
  e.T_target_cur = T_target_prev * T_prev_cur_guess;
  e.odometry = odometry_.estimate(cur, *target.odo, e.T_target_cur, weights, *target.weights);
  if (!e.odometry.ok && target.from_model) {
    // A thin or wrong prediction: the previous frame is the safer target.
    target = targets_.previousFrame();
    T_target_prev = SE3::Identity();
    e.T_target_cur = T_prev_cur_guess;
    e.odometry = odometry_.estimate(cur, *target.odo, e.T_target_cur, weights, *target.weights);
  }
  result.used_model = target.from_model;
  if (e.odometry.ok) {
    e.T_target_cur = e.odometry.T_target_source;
    e.target_depth_offset = e.odometry.target_depth_offset;
  }
  e.scores = carried;
  return e;
}

bool FlowFusionSystem::startFusion(const RgbdFrame& frame, const SE3& T_world_cam, const cv::Mat& full_scores,
                                   bool late) {
  const int every = config_.pipeline.fusion_every;
  const bool due = frames_since_fusion_ >= every;
  if (!map_ || !due || (late && frames_since_fusion_ < 2 * every)) {
    ++frames_since_fusion_;
    return false;
  }
  frames_since_fusion_ = 1;
  finishFusion();
  fusion_ = std::async(std::launch::async, [this, frame, T_world_cam, weights = staticWeights(full_scores)] {
    const Clock::time_point start = Clock::now();
    map_->integrate(frame, camera_, T_world_cam, weights);
    return msSince(start);
  });
  return true;
}

void FlowFusionSystem::applyLoopCorrections() {
  if (!slam_) return;
  for (;;) {
    std::optional<MapCorrection> c;
    {
      StageTimer timer(timings_, "loop_closure");  // waiting for a check still running when due
      c = slam_->takeCorrection();
    }
    if (!c) return;
    finishFusion();  // the map moves
    StageTimer timer(timings_, "loop_correction");
    if (map_) map_->moveSurfels(c->T_new_old_by_integration);
    targets_.moveWorld(c->T_new_old_current);
  }
}

void FlowFusionSystem::relocalize(const RgbdFrame& frame, FrameResult& result, cv::Mat& scores) {
  ++lost_frames_;
  StageTimer timer(timings_, "relocalization");
  const std::optional<SE3> found = slam_->relocalize(frame, {});
  if (!found) {
    result.message += "; lost (no keyframe matches)";
    return;
  }
  ++relocalized_frames_;
  result.T_world_cam = *found;
  result.tracking_ok = true;
  result.message = "relocalized against the keyframes";
  scores = cv::Mat();  // they were made against the failed target
  T_prev_cur_velocity_ = SE3::Identity();
  velocity_dt_ = 0;
  targets_ = TrackingTargets(config_.pipeline, config_.odometry, camera_);  // this frame starts them again
}

void FlowFusionSystem::finishLoopClosure() {
  if (!slam_) return;
  slam_->finish();
  applyLoopCorrections();
}

void FlowFusionSystem::finishFusion() const {
  if (fusion_.valid()) timings_.add("fusion", fusion_.get());
}

SE3 FlowFusionSystem::atColourTime(const RgbdFrame& frame, const SE3& T_world_cam) const {
  // The geometry dominates the odometry, so the pose found is the camera's at the depth image's time.
  if (!config_.pipeline.shift_to_colour_time || velocity_dt_ <= 0) return T_world_cam;
  const double s = (frame.timestamp - frame.depthTime()) / velocity_dt_;
  if (std::abs(s) >= 1.0) return T_world_cam;
  return orthonormalized(T_world_cam * expSE3(s * logSE3(T_prev_cur_velocity_)));
}

}  // namespace ff
