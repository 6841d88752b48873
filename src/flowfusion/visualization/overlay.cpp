#include "flowfusion/visualization/overlay.h"

#include <algorithm>

#include "flowfusion/core/error.h"

namespace ff {

cv::Mat overlayMask(const cv::Mat& bgr, const cv::Mat& mask) {
  if (bgr.type() != CV_8UC3) throw InputError("overlayMask: the colour image must be CV_8UC3");
  if (mask.size() != bgr.size() || (mask.type() != CV_8UC1 && mask.type() != CV_32FC1))
    throw InputError("overlayMask: the mask must be CV_8UC1 or CV_32FC1 of the colour image's size");
  constexpr float kTint = 0.6f;  // how far a fully dynamic pixel moves towards pure red
  cv::Mat out = bgr.clone();
  for (int y = 0; y < bgr.rows; ++y)
    for (int x = 0; x < bgr.cols; ++x) {
      const float m = mask.type() == CV_8UC1 ? (mask.at<uchar>(y, x) ? 1.0f : 0.0f)
                                             : std::clamp(mask.at<float>(y, x), 0.0f, 1.0f);
      if (m == 0) continue;
      cv::Vec3b& c = out.at<cv::Vec3b>(y, x);
      const float a = kTint * m;
      c = cv::Vec3b(cv::saturate_cast<uchar>((1 - a) * c[0]), cv::saturate_cast<uchar>((1 - a) * c[1]),
                    cv::saturate_cast<uchar>((1 - a) * c[2] + a * 255));
    }
  return out;
}

}  // namespace ff
