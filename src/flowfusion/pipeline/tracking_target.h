#pragma once
// The tracking-target policy: what the next frame is aligned to. A processed frame becomes the
// previous frame; under frame_to_keyframe it also becomes the keyframe once the camera has moved
// far enough from the last one (drift then grows per keyframe, not per frame), and with
// model_keyframes its depth is replaced by the static map's prediction at its pose. Under
// frame_to_model the map is rendered at the previous pose for every frame. Targets carry their
// static weights 1 - b, so a moving object in a target does not attract the background it covered.
#include <memory>
#include <optional>

#include "flowfusion/core/rgbd_frame.h"
#include "flowfusion/core/timings.h"
#include "flowfusion/fusion/static_map.h"
#include "flowfusion/odometry/dense_odometry.h"
#include "flowfusion/pipeline/system_config.h"

namespace ff {

// A processed frame kept as a target.
struct TrackedFrame {
  RgbdFrame frame;
  OdometryFrame odo;
  SE3 T_world_cam;
  cv::Mat scores;          // b per pixel at the segmentation level, empty when none
  cv::Mat target_weights;  // 1 - b where it serves as a target, empty for all 1
  bool from_model = false; // odo holds the map's depth predicted at T_world_cam

  // Depth image at pyramid `level` (level 0 is the input frame's own).
  const cv::Mat& depthAt(int level) const { return level == 0 ? frame.depth : odo.level(level).depth; }
};

// What one frame is aligned to.
struct TrackingTarget {
  const OdometryFrame* odo = nullptr;
  const cv::Mat* weights = nullptr;  // target weights (may be empty)
  SE3 T_world_target;
  bool from_model = false;
  std::shared_ptr<const OdometryFrame> rendered;  // owns odo when the map was rendered for it
};

class TrackingTargets {
 public:
  TrackingTargets(const PipelineOptions& options, const OdometryConfig& odometry, const CameraIntrinsics& camera);

  // The last processed frame; null before the first.
  const TrackedFrame* previous() const { return previous_.get(); }
  // The target for the next frame (call only after the first frame). Renders the map under
  // frame_to_model (timed as "prediction").
  TrackingTarget choose(const StaticMap* map, Timings& timings) const;
  // The previous frame as a target: the fallback when a rendered target fails.
  TrackingTarget previousFrame() const;
  // Keeps `frame` as the previous frame and, when the policy says so, as the keyframe. A frame
  // whose tracking failed always becomes a keyframe, and so does the first scored frame after a
  // keyframe without scores (the first frame): that keyframe's moving objects carry full weight
  // and pull every frame aligned to it. `dynamic_mask` (input size) marks the pixels that keep the
  // frame's depth in a model keyframe.
  void advance(TrackedFrame frame, bool tracking_ok, const cv::Mat& dynamic_mask, const StaticMap* map,
               Timings& timings);
  // Moves the kept frames' poses to another world frame (a loop closure's correction T_new_old);
  // a model keyframe's rendered depth stays, since the map moves with it.
  void moveWorld(const SE3& T_new_old);
  // Whether advance() with this pose, status and scores (`scored`: the frame has dynamic scores)
  // may render the map (a new model keyframe), so the map must be complete up to that frame first.
  bool rendersOnAdvance(const SE3& T_world_cam, bool tracking_ok, bool scored) const;

 private:
  // The map's depth predicted at `source`'s pose with its image as the photometric target (its
  // own depth at the `keep` pixels, where the map has none and where its own surface lies in
  // front of the map's by over 5 %); none when the prediction covers less than
  // model_min_valid_fraction of its depth pixels at the odometry's finest level.
  std::optional<OdometryFrame> modelTarget(const TrackedFrame& source, const StaticMap& map,
                                           const cv::Mat& keep = {}) const;
  bool needsKeyframe(const SE3& T_world_cam, bool tracking_ok, bool scored) const;

  PipelineOptions options_;
  OdometryConfig odometry_;
  CameraIntrinsics camera_;
  std::unique_ptr<TrackedFrame> previous_;
  std::unique_ptr<TrackedFrame> keyframe_;
};

}  // namespace ff
