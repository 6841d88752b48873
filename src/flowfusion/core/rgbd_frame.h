#pragma once
// One RGB-D observation in the units every stage uses.
#include <opencv2/core.hpp>
#include <cmath>
#include <limits>
#include <string>

namespace ff {

struct RgbdFrame {
  double timestamp = 0;  // seconds (the colour image's timestamp)
  // seconds; the depth image's own time. Colour and depth of TUM sequences are up to 20 ms
  // apart; NaN = the same as timestamp.
  double depth_timestamp = std::numeric_limits<double>::quiet_NaN();
  cv::Mat color;         // CV_8UC3, BGR (OpenCV's order)
  cv::Mat intensity;     // CV_32FC1, grey level in [0, 1]
  cv::Mat depth;         // CV_32FC1, metres along the optical axis; 0 = no measurement
  std::string name;      // where it came from (file name), for messages

  // The depth image's time, seconds: depth_timestamp, or timestamp when that is NaN.
  double depthTime() const { return std::isnan(depth_timestamp) ? timestamp : depth_timestamp; }
  int width() const { return depth.cols; }
  int height() const { return depth.rows; }
};

// Grey level (of `intensity`) below which a pixel is black: on a black screen the optical flow is
// filled in from around it or follows reflections, and tells nothing of the surface's own motion
// (the start's mover group, ConsensusConfig::start_max_black_share; the holes tested by their own
// flow, holesToTest).
constexpr float kBlackGrey = 0.1f;

// Builds a frame from a BGR image and a raw 16-bit depth image (depth_scale units per metre,
// 5000 for TUM). Sizes must match; the caller has checked types.
RgbdFrame makeRgbdFrame(double timestamp, const cv::Mat& bgr8, const cv::Mat& depth16, double depth_scale,
                        const std::string& name = {});
// Intensity in [0, 1] from BGR (ITU-R BT.601 luma, as cv::cvtColor).
cv::Mat intensityFromBgr(const cv::Mat& bgr8);
// The smallest valid depth (> 0) over the 3x3 pixels around (u, v) of a CV_32F depth image,
// clipped to the image; 0 when none has depth. What another view saw nearest at a projected point.
float smallestDepthAround(const cv::Mat& depth, int u, int v);

}  // namespace ff
