#pragma once
// One step the written-mask rules share: set the pixels of chosen labelled regions.
#include <opencv2/core.hpp>
#include <vector>

namespace ff {

// Sets mask (CV_8UC1) to `value` wherever regions (CV_32SC1 labels of mask's size, as
// cv::connectedComponents gives them) holds a label whose entry in `chosen` is non-zero.
inline void setChosenRegions(cv::Mat& mask, const cv::Mat& regions, const std::vector<uchar>& chosen, uchar value) {
  for (int v = 0; v < mask.rows; ++v) {
    const int* l = regions.ptr<int>(v);
    uchar* m = mask.ptr<uchar>(v);
    for (int u = 0; u < mask.cols; ++u)
      if (chosen[l[u]]) m[u] = value;
  }
}

}  // namespace ff
