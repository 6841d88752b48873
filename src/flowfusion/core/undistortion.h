#pragma once
// Lens undistortion of RGB-D images. The pipeline's stages all use the pinhole model; with a
// distorted lens (TUM fr1: up to ~20 px at the image corners) the same surface lands at
// different rays in different views, which a single frame-to-frame alignment mostly absorbs
// but a map fused over many views does not: on the shared fr1/xyz frames, frame-to-model
// tracking went from 16.2 mm ATE on the raw images to 13.7 mm undistorted.
#include <opencv2/core.hpp>

#include "flowfusion/core/camera.h"
#include "flowfusion/core/rgbd_frame.h"

namespace ff {

class Undistorter {
 public:
  // Maps for `camera` (the undistorted image keeps its intrinsics and size) and `distortion`.
  Undistorter(const CameraIntrinsics& camera, const LensDistortion& distortion);

  // The images a pinhole camera with the same intrinsics would have taken. Colour bilinear,
  // raw 16-bit depth nearest (an average across a depth edge would invent a surface between the
  // two); pixels whose ray leaves the raw image have no depth (their colour repeats the border,
  // so that the rim of the image is not darkened by blending with black).
  cv::Mat undistortColor(const cv::Mat& bgr8) const;
  cv::Mat undistortDepth(const cv::Mat& depth16) const;
  // An image in undistorted pixels (a mask, an overlay) back in the raw image's pixels (nearest).
  cv::Mat toRawPixels(const cv::Mat& image) const;

 private:
  cv::Mat undistort_x_, undistort_y_;  // CV_32F, raw-image coordinates of each undistorted pixel
  cv::Mat raw_x_, raw_y_;              // CV_32F, undistorted coordinates of each raw pixel
};

}  // namespace ff
