#include "flowfusion/visualization/mask_sheet.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>

#include "flowfusion/core/error.h"
#include "flowfusion/visualization/overlay.h"

namespace ff {
namespace {

constexpr int kTitleHeightPx = 28;
constexpr int kColumns = 5;  // colour, depth, true mask, estimate, comparison
constexpr double kDim = 0.5;  // how far the comparison dims the frame under its colours

void checkRow(const MaskSheetRow& r, size_t index) {
  const std::string where = "mask sheet row " + std::to_string(index) + ": ";
  if (r.color.type() != CV_8UC3 || r.color.empty()) throw InputError(where + "the colour image must be CV_8UC3");
  if (r.depth.type() != CV_32FC1 || r.depth.size() != r.color.size())
    throw InputError(where + "the depth must be CV_32FC1 of the colour image's size");
  for (const cv::Mat* m : {&r.gt_mask, &r.est_mask})
    if (m->type() != CV_8UC1 || m->size() != r.color.size())
      throw InputError(where + "the masks must be CV_8UC1 of the colour image's size");
}

// Largest valid depth over all rows (at least 1 m), the colour scale of the depth column.
double depthRange(const std::vector<MaskSheetRow>& rows) {
  double max_depth = 1.0;
  for (const MaskSheetRow& r : rows) {
    double lo = 0, hi = 0;
    cv::minMaxLoc(r.depth, &lo, &hi, nullptr, nullptr, r.depth > 0);
    if (std::isfinite(hi)) max_depth = std::max(max_depth, hi);
  }
  return std::ceil(max_depth * 2) / 2;  // half metres, for a readable title
}

void putLabel(cv::Mat& image, const std::string& text, cv::Point at) {
  // Dark outline under light text, readable on any frame.
  cv::putText(image, text, at, cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0), 3, cv::LINE_AA);
  cv::putText(image, text, at, cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
}

cv::Mat scaled(const cv::Mat& image, int width_px, int interpolation) {
  cv::Mat out;
  const double f = static_cast<double>(width_px) / image.cols;
  cv::resize(image, out, cv::Size(width_px, std::max(1, static_cast<int>(std::lround(image.rows * f)))), 0, 0,
             interpolation);
  return out;
}

cv::Mat sheetRow(const MaskSheetRow& r, double max_depth_m, int width_px) {
  const cv::Mat columns[kColumns] = {r.color, depthColormap(r.depth, max_depth_m),
                                     overlayMask(r.color, r.gt_mask > 127), overlayMask(r.color, r.est_mask > 127),
                                     maskComparison(r.color, r.gt_mask, r.est_mask)};
  std::vector<cv::Mat> small;
  for (const cv::Mat& c : columns) small.push_back(scaled(c, width_px, cv::INTER_AREA));
  int line = 0;
  for (size_t start = 0; start <= r.label.size(); ++line) {
    const size_t end = std::min(r.label.find('\n', start), r.label.size());
    putLabel(small[0], r.label.substr(start, end - start), cv::Point(6, 18 + 18 * line));
    start = end + 1;
  }
  cv::Mat out;
  cv::hconcat(small, out);
  return out;
}

cv::Mat titleStrip(int width_px, double max_depth_m, int column_width_px) {
  cv::Mat strip(kTitleHeightPx, width_px, CV_8UC3, cv::Scalar(40, 40, 40));
  char depth_title[64];
  std::snprintf(depth_title, sizeof depth_title, "depth 0-%.1f m (blue near)", max_depth_m);
  const std::string titles[kColumns] = {"colour", depth_title, "true mask", "estimated mask",
                                        "green hit, red missed, blue false"};
  for (int c = 0; c < kColumns; ++c) putLabel(strip, titles[c], cv::Point(c * column_width_px + 6, 19));
  return strip;
}

}  // namespace

cv::Mat maskComparison(const cv::Mat& bgr, const cv::Mat& gt_mask, const cv::Mat& est_mask) {
  if (bgr.type() != CV_8UC3 || gt_mask.type() != CV_8UC1 || est_mask.type() != CV_8UC1 ||
      gt_mask.size() != bgr.size() || est_mask.size() != bgr.size())
    throw InputError("maskComparison: a CV_8UC3 frame and two CV_8UC1 masks of its size are needed");
  cv::Mat out;
  bgr.convertTo(out, CV_8UC3, kDim);
  const cv::Mat gt = gt_mask > 127, est = est_mask > 127;
  out.setTo(cv::Scalar(0, 200, 0), gt & est);
  out.setTo(cv::Scalar(0, 0, 255), gt & ~est);
  out.setTo(cv::Scalar(255, 64, 0), ~gt & est);
  return out;
}

cv::Mat depthColormap(const cv::Mat& depth_m, double max_depth_m) {
  if (depth_m.type() != CV_32FC1) throw InputError("depthColormap: the depth must be CV_32FC1 metres");
  if (!(max_depth_m > 0)) throw InputError("depthColormap: the depth range must be positive");
  cv::Mat grey, out;
  depth_m.convertTo(grey, CV_8U, 255.0 / max_depth_m);
  cv::applyColorMap(grey, out, cv::COLORMAP_JET);
  out.setTo(cv::Scalar(0, 0, 0), ~(depth_m > 0));
  return out;
}

cv::Mat maskContactSheet(const std::vector<MaskSheetRow>& rows, int column_width_px) {
  if (rows.empty()) throw InputError("mask sheet: no frames to show");
  if (column_width_px < 64) throw InputError("mask sheet: the column width must be at least 64 px");
  for (size_t i = 0; i < rows.size(); ++i) checkRow(rows[i], i);
  const double max_depth_m = depthRange(rows);
  std::vector<cv::Mat> strips{titleStrip(kColumns * column_width_px, max_depth_m, column_width_px)};
  for (const MaskSheetRow& r : rows) strips.push_back(sheetRow(r, max_depth_m, column_width_px));
  cv::Mat sheet;
  cv::vconcat(strips, sheet);
  return sheet;
}

}  // namespace ff
