#include "flowfusion/core/rgbd_frame.h"

#include <opencv2/imgproc.hpp>

namespace ff {

cv::Mat intensityFromBgr(const cv::Mat& bgr8) {
  cv::Mat gray, out;
  cv::cvtColor(bgr8, gray, cv::COLOR_BGR2GRAY);
  gray.convertTo(out, CV_32F, 1.0 / 255.0);
  return out;
}

RgbdFrame makeRgbdFrame(double timestamp, const cv::Mat& bgr8, const cv::Mat& depth16, double depth_scale,
                        const std::string& name) {
  RgbdFrame f;
  f.timestamp = timestamp;
  f.color = bgr8;
  f.intensity = intensityFromBgr(bgr8);
  depth16.convertTo(f.depth, CV_32F, 1.0 / depth_scale);
  f.name = name;
  return f;
}

}  // namespace ff
