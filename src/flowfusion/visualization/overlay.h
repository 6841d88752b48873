#pragma once
// A frame with its dynamic pixels tinted, for looking at masks.
#include <opencv2/core.hpp>

namespace ff {

// Colour frame with the dynamic pixels tinted red. mask: CV_8UC1 (non-zero = dynamic) or CV_32FC1
// (dynamic score in [0, 1]), same size as bgr.
cv::Mat overlayMask(const cv::Mat& bgr, const cv::Mat& mask);

}  // namespace ff
