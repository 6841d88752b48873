#pragma once
// Where dynamic masks fail, in pictures: a contact sheet with one row per frame showing the colour
// image, its depth, the true mask, the estimated mask and the two compared (green where both are
// dynamic, red where the estimate missed a dynamic pixel, blue where it marked a static one).
// `flowfusion eval seg --sheet` fills it with the worst frames (report/worst_masks.h).
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace ff {

struct MaskSheetRow {
  cv::Mat color;     // CV_8UC3, BGR
  cv::Mat depth;     // CV_32FC1, metres, 0 = no measurement; the colour image's size
  cv::Mat gt_mask;   // CV_8UC1, > 127 = dynamic; the colour image's size
  cv::Mat est_mask;  // likewise
  std::string label;  // written over the colour image (timestamp, scores); '\n' starts a line
};

// The masks compared over the dimmed frame: true positives green, false negatives red, false
// positives blue. All of one size (throws InputError otherwise).
cv::Mat maskComparison(const cv::Mat& bgr, const cv::Mat& gt_mask, const cv::Mat& est_mask);

// Depth in colour from near (blue) to max_depth_m (red), black where there is no measurement.
cv::Mat depthColormap(const cv::Mat& depth_m, double max_depth_m);

// A title strip naming the columns (and the depth range, shared by all rows), then one row per
// MaskSheetRow with each image scaled to column_width_px. Throws InputError on an empty list, a
// bad size or type (naming the row), or a column width below 64 px.
cv::Mat maskContactSheet(const std::vector<MaskSheetRow>& rows, int column_width_px = 320);

}  // namespace ff
