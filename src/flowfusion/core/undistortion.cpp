#include "flowfusion/core/undistortion.h"

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

namespace ff {

namespace {

cv::Mat cvDistortion(const LensDistortion& d) { return (cv::Mat_<double>(1, 5) << d.k1, d.k2, d.p1, d.p2, d.k3); }

}  // namespace

Undistorter::Undistorter(const CameraIntrinsics& camera, const LensDistortion& distortion) {
  cv::Mat K;
  cv::eigen2cv(camera.K(), K);
  const cv::Mat D = cvDistortion(distortion);
  const cv::Size size(camera.width, camera.height);
  cv::initUndistortRectifyMap(K, D, cv::Mat(), K, size, CV_32FC1, undistort_x_, undistort_y_);
  // The inverse map: where each raw pixel lands once undistorted (iterative inversion by OpenCV).
  std::vector<cv::Point2f> raw;
  raw.reserve(size.area());
  for (int v = 0; v < size.height; ++v)
    for (int u = 0; u < size.width; ++u) raw.emplace_back(static_cast<float>(u), static_cast<float>(v));
  std::vector<cv::Point2f> undistorted;
  cv::undistortPoints(raw, undistorted, K, D, cv::noArray(), K);
  raw_x_.create(size, CV_32FC1);
  raw_y_.create(size, CV_32FC1);
  for (int v = 0, i = 0; v < size.height; ++v)
    for (int u = 0; u < size.width; ++u, ++i) {
      raw_x_.at<float>(v, u) = undistorted[i].x;
      raw_y_.at<float>(v, u) = undistorted[i].y;
    }
}

cv::Mat Undistorter::undistortColor(const cv::Mat& bgr8) const {
  cv::Mat out;
  cv::remap(bgr8, out, undistort_x_, undistort_y_, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  return out;
}

cv::Mat Undistorter::undistortDepth(const cv::Mat& depth16) const {
  cv::Mat out;
  cv::remap(depth16, out, undistort_x_, undistort_y_, cv::INTER_NEAREST, cv::BORDER_CONSTANT, cv::Scalar::all(0));
  return out;
}

cv::Mat Undistorter::toRawPixels(const cv::Mat& image) const {
  cv::Mat out;
  cv::remap(image, out, raw_x_, raw_y_, cv::INTER_NEAREST, cv::BORDER_CONSTANT, cv::Scalar::all(0));
  return out;
}

}  // namespace ff
