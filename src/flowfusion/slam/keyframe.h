#pragma once
// A keyframe of the loop closer: the images a place is recognised and checked by, small and
// compact (8-bit intensity, 16-bit depth at 1/5000 m, an 8-bit static weight, at one pyramid
// level of the input), immutable once made so that the tracking thread and the back end share it.
// Only what the dynamic scores call static counts: a person walking through neither makes nor
// breaks a loop.
#include <memory>
#include <opencv2/core.hpp>

#include "flowfusion/core/camera.h"
#include "flowfusion/core/rgbd_frame.h"
#include "flowfusion/core/se3.h"
#include "flowfusion/odometry/dense_odometry.h"
#include "flowfusion/slam/slam_config.h"

namespace ff {

struct KeyframeImages {
  CameraIntrinsics camera;   // at the kept level
  cv::Mat intensity;         // CV_8U, grey * 255
  cv::Mat depth;             // CV_16U, 1/5000 m, 0 = none
  cv::Mat static_weight;     // CV_8U, (1 - b) * 255
  cv::Mat small_bgr;         // CV_8UC3, the place index's image
  cv::Mat small_depth;       // CV_32F, metres, 0 = none or dynamic

  // The kept images as the odometry takes them (intensity in [0, 1], depth in metres).
  OdometryFrame odometryFrame(const OdometryConfig& config) const;
  // (1 - b) in [0, 1] at the kept level.
  cv::Mat staticWeights() const;
};

// A keyframe as a run leaves it for the next (slam/map_file.h): its pose after the last loop
// closure and its images.
struct SavedKeyframe {
  SE3 T_world_kf;
  std::shared_ptr<const KeyframeImages> images;
};

// The frame's images at config.keyframe_level; `scores` is b per pixel at any level (empty: all
// static). Pixels with b >= 0.5 hold no depth in the place index's image.
std::shared_ptr<const KeyframeImages> makeKeyframeImages(const RgbdFrame& frame, const CameraIntrinsics& camera,
                                                         const cv::Mat& scores, const SlamConfig& config);

}  // namespace ff
