#include "flowfusion/segmentation/mask_edges.h"

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "flowfusion/core/error.h"

namespace ff {

namespace {

cv::Mat windowSum(const cv::Mat& m, int radius_px) {
  cv::Mat out;
  cv::boxFilter(m, out, -1, cv::Size(2 * radius_px + 1, 2 * radius_px + 1), cv::Point(-1, -1), false,
                cv::BORDER_CONSTANT);
  return out;
}

// Window means of `value` (1 or 3 channels) over the pixels where `weight` (CV_32F, 0 or 1) is 1,
// given their number `count` (windowSum of `weight`); 0 where there are none.
cv::Mat windowMean(const cv::Mat& value, const cv::Mat& weight, const cv::Mat& count, int radius_px) {
  cv::Mat mean, w = weight, n = cv::max(count, 1.f);
  if (value.channels() == 3) {
    cv::merge(std::vector<cv::Mat>(3, weight), w);
    cv::merge(std::vector<cv::Mat>(3, n), n);
  }
  cv::divide(windowSum(value.mul(w), radius_px), n, mean);
  return mean;
}

// The edge's pixels with depth: the side whose mean depth is nearer, across a depth step.
void byDepth(cv::Mat& mask, const cv::Mat& z, const cv::Mat& dynamic, const cv::Mat& at_edge, int radius_px) {
  cv::Mat valid;
  cv::threshold(z, valid, 0.0, 1.0, cv::THRESH_BINARY);
  const cv::Mat on_dynamic = valid.mul(dynamic), on_static = valid - on_dynamic;
  const cv::Mat n_dynamic = windowSum(on_dynamic, radius_px), n_static = windowSum(on_static, radius_px);
  const cv::Mat z_dynamic = windowMean(z, on_dynamic, n_dynamic, radius_px);
  const cv::Mat z_static = windowMean(z, on_static, n_static, radius_px);
  for (int v = 0; v < mask.rows; ++v)
    for (int u = 0; u < mask.cols; ++u) {
      const float d = z.at<float>(v, u), zd = z_dynamic.at<float>(v, u), zs = z_static.at<float>(v, u);
      if (!at_edge.at<uint8_t>(v, u) || !(d > 0) || n_dynamic.at<float>(v, u) < 0.5f ||
          n_static.at<float>(v, u) < 0.5f || std::abs(zd - zs) <= kEdgeDepthStep * d)
        continue;
      mask.at<uint8_t>(v, u) = std::abs(d - zd) < std::abs(d - zs) ? 255 : 0;
    }
}

// The pixels of each side within the window (over all pixels, with depth or not).
struct Sides {
  cv::Mat dynamic, static_;     // CV_32F, 1 on the side's pixels
  cv::Mat n_dynamic, n_static;  // their window sums
};

// The edge's pixels without depth: the side whose mean colour is nearer, across a colour step.
void byColour(cv::Mat& mask, const cv::Mat& z, const cv::Mat& bgr, const Sides& sides, const cv::Mat& at_edge,
              int radius_px) {
  cv::Mat lab8, lab;
  cv::cvtColor(bgr, lab8, cv::COLOR_BGR2Lab);
  lab8.convertTo(lab, CV_32FC3, 1.0 / 255.0);
  const cv::Mat c_dynamic = windowMean(lab, sides.dynamic, sides.n_dynamic, radius_px);
  const cv::Mat c_static = windowMean(lab, sides.static_, sides.n_static, radius_px);
  for (int v = 0; v < mask.rows; ++v)
    for (int u = 0; u < mask.cols; ++u) {
      if (!at_edge.at<uint8_t>(v, u) || z.at<float>(v, u) > 0) continue;
      const cv::Vec3f c = lab.at<cv::Vec3f>(v, u), cd = c_dynamic.at<cv::Vec3f>(v, u), cs = c_static.at<cv::Vec3f>(v, u);
      if (cv::norm(cd - cs) <= kEdgeColourStep) continue;
      mask.at<uint8_t>(v, u) = cv::norm(c - cd) < cv::norm(c - cs) ? 255 : 0;
    }
}

}  // namespace

void refineMaskEdges(cv::Mat& mask, const cv::Mat& depth, const cv::Mat& bgr, int radius_px) {
  if (mask.type() != CV_8UC1 || depth.type() != CV_32FC1 || mask.size() != depth.size() ||
      (!bgr.empty() && (bgr.type() != CV_8UC3 || bgr.size() != mask.size())))
    throw InputError("refineMaskEdges: need a CV_8UC1 mask, CV_32FC1 depth and CV_8UC3 colour (or none) of one size");
  if (radius_px < 0) throw InputError("refineMaskEdges: the radius must be >= 0");
  if (radius_px == 0 || cv::countNonZero(mask) == 0) return;
  // Every window that holds a dynamic pixel lies within twice the radius of the marked pixels.
  const int reach = 2 * radius_px;
  const cv::Rect roi = (cv::boundingRect(mask) + cv::Point(-reach, -reach) + cv::Size(2 * reach, 2 * reach)) &
                       cv::Rect(0, 0, mask.cols, mask.rows);
  cv::Mat part = mask(roi);
  Sides sides;
  cv::threshold(part, sides.dynamic, 0, 1, cv::THRESH_BINARY);
  sides.dynamic.convertTo(sides.dynamic, CV_32F);
  sides.static_ = 1.f - sides.dynamic;
  sides.n_dynamic = windowSum(sides.dynamic, radius_px);
  sides.n_static = windowSum(sides.static_, radius_px);
  const cv::Mat at_edge = (sides.n_dynamic > 0.5f) & (sides.n_static > 0.5f);
  // Both read the sides as given and write only pixels of their own kind.
  byDepth(part, depth(roi), sides.dynamic, at_edge, radius_px);
  if (!bgr.empty()) byColour(part, depth(roi), bgr(roi), sides, at_edge, radius_px);
}

}  // namespace ff
