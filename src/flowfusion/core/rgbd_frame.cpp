#include "flowfusion/core/rgbd_frame.h"

#include <algorithm>
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

float smallestDepthAround(const cv::Mat& depth, int u, int v) {
  float smallest = 0;
  for (int y = std::max(0, v - 1); y <= std::min(depth.rows - 1, v + 1); ++y)
    for (int x = std::max(0, u - 1); x <= std::min(depth.cols - 1, u + 1); ++x) {
      const float d = depth.at<float>(y, x);
      if (d > 0 && (smallest == 0 || d < smallest)) smallest = d;
    }
  return smallest;
}

}  // namespace ff
