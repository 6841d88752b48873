#pragma once
// Steps the written-mask rules share over labelled regions: count the pixels of each that lie in
// another mask, and set the pixels of chosen regions.
#include <opencv2/core.hpp>
#include <vector>

namespace ff {

// Per region of `regions` (CV_32SC1 labels 0..n-1, as cv::connectedComponents gives them; 0 is
// the background and counts nothing), how many of its pixels are non-zero in `where` (CV_8UC1 of
// the regions' size; empty: none).
inline std::vector<int> pixelsPerRegionWhere(const cv::Mat& regions, int n, const cv::Mat& where) {
  std::vector<int> count(n, 0);
  if (where.empty()) return count;
  for (int v = 0; v < regions.rows; ++v) {
    const int* r = regions.ptr<int>(v);
    const uchar* w = where.ptr<uchar>(v);
    for (int u = 0; u < regions.cols; ++u)
      if (r[u] > 0 && w[u]) ++count[r[u]];
  }
  return count;
}

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
