#pragma once
// The per-frame FlowFusion system (paper Fig. 1): robust odometry against a tracking target, the
// segmentation loop (flow, clusters, dynamic scores, weighted odometry), fusion of the static
// background into a surfel map. docs/design.md draws the pipeline and its frame conventions.
#include <memory>
#include <string>

#include "flowfusion/core/camera.h"
#include "flowfusion/core/rgbd_frame.h"
#include "flowfusion/core/timings.h"
#include "flowfusion/fusion/static_map.h"
#include "flowfusion/io/trajectory_io.h"
#include "flowfusion/pipeline/segmentation_loop.h"
#include "flowfusion/pipeline/system_config.h"
#include "flowfusion/pipeline/tracking_target.h"

namespace ff {

struct FrameResult {
  double timestamp = 0;
  SE3 T_world_cam = SE3::Identity();
  bool tracking_ok = true;
  std::string message;          // what the tracker did when it did not simply succeed
  bool used_model = false;      // aligned to the map prediction (frame_to_model or a model keyframe)
  bool restarted_from_flow = false;  // the odometry was restarted from the flow's rigid consensus
  int iterations = 0;           // segmentation rounds
  cv::Mat dynamic_mask;         // CV_8U, input size, 255 = dynamic, in this frame's pixels
  cv::Mat scores;               // CV_32F b per pixel at the segmentation level (empty when off)
};

class FlowFusionSystem {
 public:
  // Throws InputError naming the first bad setting.
  FlowFusionSystem(const SystemConfig& config, const CameraIntrinsics& camera,
                   const SE3& T_world_first = SE3::Identity());

  // Processes the next frame (in time order) and returns its pose and mask. Stage times are added
  // to timings() under "odometry", "flow", "consensus", "clustering", "scores", "prediction", "fusion".
  FrameResult process(const RgbdFrame& frame);

  const Trajectory& trajectory() const { return trajectory_; }
  const StaticMap* map() const { return map_.get(); }
  Timings& timings() { return timings_; }
  const Timings& timings() const { return timings_; }
  const SystemConfig& config() const { return config_; }
  const CameraIntrinsics& camera() const { return camera_; }
  int trackingFailures() const { return failures_; }
  int flowRestarts() const { return flow_restarts_; }

 private:
  OdometryFrame prepare(const RgbdFrame& frame);
  // The odometry against the chosen target from the guess T_prev_cur_guess, weighted by the
  // carried scores; a rendered target that fails gives way to the previous frame.
  MotionEstimate firstOdometry(const OdometryFrame& cur, TrackingTarget& target, SE3& T_target_prev,
                               const SE3& T_prev_cur_guess, const cv::Mat& carried, FrameResult& result);
  // Odometry and segmentation against the target; returns the scores (empty without segmentation).
  cv::Mat track(const RgbdFrame& frame, const OdometryFrame& cur, FrameResult& result);
  void fuse(const RgbdFrame& frame, const SE3& T_world_cam, const cv::Mat& full_scores);
  // The pose reported at the colour image's time, moved from the depth image's along the last motion.
  SE3 atColourTime(const RgbdFrame& frame, const SE3& T_world_cam) const;

  SystemConfig config_;
  CameraIntrinsics camera_;
  DenseOdometry odometry_;
  std::unique_ptr<SegmentationLoop> segmentation_;
  std::unique_ptr<StaticMap> map_;
  TrackingTargets targets_;
  SE3 T_world_first_;
  SE3 T_prev_cur_velocity_ = SE3::Identity();  // last frame-to-frame motion, the next guess
  double velocity_dt_ = 0;                      // s, the time that motion took
  Trajectory trajectory_;
  Timings timings_;
  int failures_ = 0;
  int flow_restarts_ = 0;
};

}  // namespace ff
