#include "flowfusion/segmentation/depth_holes.h"

#include <opencv2/imgproc.hpp>
#include <vector>

#include "flowfusion/core/error.h"
#include "flowfusion/segmentation/region_labels.h"

namespace ff {

namespace {

bool hasDepth(float z) { return z > 0; }  // false for NaN too

}  // namespace

void fillDepthHoles(cv::Mat& mask, const cv::Mat& depth, double min_dynamic_share) {
  if (mask.type() != CV_8UC1 || depth.type() != CV_32FC1 || mask.size() != depth.size())
    throw InputError("fillDepthHoles: the mask must be CV_8UC1 and the depth CV_32FC1 of the same size");
  if (!(min_dynamic_share > 0 && min_dynamic_share <= 1))
    throw InputError("fillDepthHoles: min_dynamic_share must be in (0, 1]");
  cv::Mat holes(depth.size(), CV_8U);
  for (int v = 0; v < depth.rows; ++v) {
    const float* z = depth.ptr<float>(v);
    uchar* h = holes.ptr<uchar>(v);
    for (int u = 0; u < depth.cols; ++u) h[u] = hasDepth(z[u]) ? 0 : 255;
  }
  cv::Mat regions;
  const int n = cv::connectedComponents(holes, regions, 4, CV_32S);
  if (n <= 1) return;
  // Per region (label 0 is the pixels with depth): its neighbours with depth, and the dynamic ones.
  std::vector<int> neighbours(n, 0), dynamic(n, 0);
  const int W = depth.cols, H = depth.rows;
  auto count = [&](int region, int v, int u) {
    if (region == 0) return;
    ++neighbours[region];
    dynamic[region] += mask.at<uchar>(v, u) > 0;
  };
  for (int v = 0; v < H; ++v) {
    const float* z = depth.ptr<float>(v);
    for (int u = 0; u < W; ++u) {
      if (!hasDepth(z[u])) continue;
      if (u > 0) count(regions.at<int>(v, u - 1), v, u);
      if (u + 1 < W) count(regions.at<int>(v, u + 1), v, u);
      if (v > 0) count(regions.at<int>(v - 1, u), v, u);
      if (v + 1 < H) count(regions.at<int>(v + 1, u), v, u);
    }
  }
  std::vector<uchar> fill(n, 0);
  bool any = false;
  for (int r = 1; r < n; ++r) {
    fill[r] = neighbours[r] > 0 && dynamic[r] >= min_dynamic_share * neighbours[r];
    any = any || fill[r];
  }
  if (any) setChosenRegions(mask, regions, fill, 255);
}

}  // namespace ff
