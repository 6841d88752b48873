#include "flowfusion/pipeline/tracking_target.h"

#include <opencv2/imgproc.hpp>

namespace ff {

TrackingTargets::TrackingTargets(const PipelineOptions& options, const OdometryConfig& odometry,
                                 const CameraIntrinsics& camera)
    : options_(options), odometry_(odometry), camera_(camera) {}

TrackingTarget TrackingTargets::previousFrame() const {
  return {&previous_->odo, &previous_->target_weights, previous_->T_world_cam, previous_->from_model, nullptr};
}

TrackingTarget TrackingTargets::choose(const StaticMap* map, Timings& timings) const {
  if (options_.tracking == TrackingMode::FrameToKeyframe && keyframe_)
    return {&keyframe_->odo, &keyframe_->target_weights, keyframe_->T_world_cam, keyframe_->from_model, nullptr};
  if (options_.tracking == TrackingMode::FrameToModel && map && map->size() > 0) {
    StageTimer timer(timings, "prediction");
    if (auto predicted = modelTarget(*previous_, *map)) {
      // A rendered target has no moving objects, so no target weights.
      static const cv::Mat kNoWeights;
      auto rendered = std::make_shared<const OdometryFrame>(std::move(*predicted));
      return {rendered.get(), &kNoWeights, previous_->T_world_cam, true, rendered};
    }
  }
  return previousFrame();
}

std::optional<OdometryFrame> TrackingTargets::modelTarget(const TrackedFrame& source, const StaticMap& map,
                                                          const cv::Mat& keep) const {
  // Rendered at the odometry's finest level (the finer input levels are never aligned) and
  // brought to the input size, where the pyramid's 2x2 averages give it back unchanged.
  const int finest = odometry_.finest_level;
  const cv::Mat predicted = map.predictDepth(source.T_world_cam, camera_.atLevel(finest));
  const double covered = cv::countNonZero(predicted > 0);
  const double needed = options_.model_min_valid_fraction * cv::countNonZero(source.depthAt(finest) > 0);
  if (covered < needed) return std::nullopt;
  // The model's depth is averaged over many frames (less noise, less drift); its colour is
  // blurred by the surfel splats, so the frame's own image stays the photometric target.
  const RgbdFrame& frame = source.frame;
  cv::Mat depth;
  cv::resize(predicted, depth, frame.depth.size(), 0, 0, cv::INTER_NEAREST);
  frame.depth.copyTo(depth, depth <= 0);
  if (!keep.empty()) frame.depth.copyTo(depth, keep);
  // A surface the frame sees in front of the map's is one the map does not hold yet (a static
  // object just come into view, not yet stable there): without it the target would show the
  // background behind it, and the object would leave a depth residual in every frame aligned here.
  constexpr double kInFrontRatio = 0.05;  // of the map's depth
  frame.depth.copyTo(depth, (frame.depth > 0) & (frame.depth < depth * (1.0 - kInFrontRatio)));
  return prepareOdometryFrame(frame.intensity, depth, camera_, odometry_);
}

bool TrackingTargets::needsKeyframe(const SE3& T_world_cam, bool tracking_ok, bool scored) const {
  if (!keyframe_ || !tracking_ok || (scored && keyframe_->scores.empty())) return true;
  const SE3 T_kf_cur = keyframe_->T_world_cam.inverse() * T_world_cam;
  return translationNorm(T_kf_cur) > options_.keyframe_translation ||
         rotationAngleDeg(T_kf_cur) > options_.keyframe_rotation_deg;
}

bool TrackingTargets::rendersOnAdvance(const SE3& T_world_cam, bool tracking_ok, bool scored) const {
  return options_.tracking == TrackingMode::FrameToKeyframe && options_.model_keyframes &&
         needsKeyframe(T_world_cam, tracking_ok, scored);
}

void TrackingTargets::advance(TrackedFrame frame, bool tracking_ok, const cv::Mat& dynamic_mask,
                              const StaticMap* map, Timings& timings) {
  const bool scored = !frame.scores.empty();
  if (options_.tracking == TrackingMode::FrameToKeyframe && needsKeyframe(frame.T_world_cam, tracking_ok, scored)) {
    keyframe_ = std::make_unique<TrackedFrame>(frame);
    if (options_.model_keyframes && map && map->size() > 0) {
      StageTimer timer(timings, "prediction");
      // The map has no moving objects; the keyframe's image has, so their pixels keep its depth.
      if (auto predicted = modelTarget(*keyframe_, *map, dynamic_mask)) {
        keyframe_->odo = std::move(*predicted);
        keyframe_->from_model = true;
      }
    }
  }
  previous_ = std::make_unique<TrackedFrame>(std::move(frame));
}

void TrackingTargets::moveWorld(const SE3& T_new_old) {
  if (previous_) previous_->T_world_cam = orthonormalized(T_new_old * previous_->T_world_cam);
  if (keyframe_) keyframe_->T_world_cam = orthonormalized(T_new_old * keyframe_->T_world_cam);
}

}  // namespace ff
