#pragma once
// OpenCV's frame-to-frame RGB-D odometry (opencv_contrib rgbd module) with library defaults: the
// "peer" baseline columns of `flowfusion bench`. RgbdOdometry is direct photometric + depth
// alignment (Steinbruecker et al. 2011), RgbdICPOdometry is point-to-plane ICP; neither handles
// dynamic objects, which is what FlowFusion is compared against.
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "flowfusion/core/camera.h"
#include "flowfusion/core/rgbd_frame.h"
#include "flowfusion/io/trajectory_io.h"

namespace ff {
class TumSequence;
}

namespace ff::eval {

// OpenCV's odometries, the peers `bench` measures against.
enum class ReferenceMethod {
  RgbdOdometry,     // cv::rgbd::RgbdOdometry (photometric)
  RgbdIcpOdometry,  // cv::rgbd::RgbdICPOdometry (photometric + ICP)
};
// "opencv-RgbdOdometry" or "opencv-RgbdICPOdometry", as bench's table names them.
std::string methodName(ReferenceMethod method);

class ReferenceOdometry {
 public:
  // The first tracked frame gets T_world_first.
  ReferenceOdometry(ReferenceMethod method, const CameraIntrinsics& camera, const SE3& T_world_first = SE3::Identity());
  ~ReferenceOdometry();
  ReferenceOdometry(const ReferenceOdometry&) = delete;
  ReferenceOdometry& operator=(const ReferenceOdometry&) = delete;

  // Aligns the frame to the previous one and returns its T_world_cam. When OpenCV reports failure
  // the previous frame-to-frame motion is repeated (constant velocity; identity after the first
  // frame) and failures() counts it. The frame must have the camera's size (InputError naming
  // frame.name otherwise).
  SE3 track(const RgbdFrame& frame);

  const Trajectory& trajectory() const { return trajectory_; }
  int failures() const { return failures_; }
  // Wall time of each odometry call (frame preparation included), ms; one per frame after the first.
  const std::vector<double>& callMs() const { return call_ms_; }
  double medianMs() const;
  ReferenceMethod method() const { return method_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  ReferenceMethod method_;
  CameraIntrinsics camera_;
  SE3 T_world_first_;
  SE3 T_prev_cur_ = SE3::Identity();  // last frame-to-frame motion, for failures
  Trajectory trajectory_;
  std::vector<double> call_ms_;
  int failures_ = 0;
};

struct ReferenceRun {
  Trajectory trajectory;
  int failures = 0;
  double median_ms = 0;  // per odometry call
};

// Runs ReferenceOdometry over the first max_frames frames of a sequence (all when nullopt),
// starting at the ground-truth pose of the first frame when the sequence has ground truth
// within 0.02 s, else at identity.
ReferenceRun runReferenceOdometry(ReferenceMethod method, const TumSequence& sequence,
                                  std::optional<size_t> max_frames = std::nullopt);

}  // namespace ff::eval
