#include "flowfusion/core/sensor_band.h"

#include <algorithm>

#include "flowfusion/core/error.h"

namespace ff {

SensorBand SensorBand::of(const cv::Mat& depth) {
  if (depth.type() != CV_32FC1) throw InputError("SensorBand: the depth must be CV_32FC1");
  cv::Mat without;
  cv::Mat(~(depth > 0.f)).convertTo(without, CV_32F, 1.0 / 255);
  cv::Mat row_share, col_share;
  cv::reduce(without, row_share, 1, cv::REDUCE_AVG);  // rows x 1
  cv::reduce(without, col_share, 0, cv::REDUCE_AVG);  // 1 x cols
  // The lines from one edge inward (step +1 from the first, -1 from the last) mostly without depth.
  const auto width = [](const cv::Mat& share, int first, int step) {
    const int n = static_cast<int>(share.total()), most = n / kBandMaxFraction;
    int w = 0;
    while (w < most && share.at<float>(first + step * w) >= kBandMinShare) ++w;
    return w;
  };
  const int rows = depth.rows, cols = depth.cols;
  return {width(row_share, 0, 1), width(row_share, rows - 1, -1), width(col_share, 0, 1),
          width(col_share, cols - 1, -1)};
}

cv::Mat SensorBand::pixels(cv::Size size) const {
  cv::Mat band(size, CV_8U, cv::Scalar(0));
  band.rowRange(0, std::min(top, size.height)).setTo(255);
  band.rowRange(std::max(0, size.height - bottom), size.height).setTo(255);
  band.colRange(0, std::min(left, size.width)).setTo(255);
  band.colRange(std::max(0, size.width - right), size.width).setTo(255);
  return band;
}

void SensorBandMedian::add(const SensorBand& b) {
  const int widths[4] = {b.top, b.bottom, b.left, b.right};
  for (int e = 0; e < 4; ++e) {
    std::vector<int>& c = counts_[e];
    if (static_cast<int>(c.size()) <= widths[e]) c.resize(widths[e] + 1, 0);
    ++c[widths[e]];
  }
  ++frames_;
}

SensorBand SensorBandMedian::median() const {
  int widths[4] = {0, 0, 0, 0};
  for (int e = 0; e < 4; ++e)
    for (int w = 0, below = 0; w < static_cast<int>(counts_[e].size()); ++w) {
      below += counts_[e][w];
      if (2 * below >= frames_) {
        widths[e] = w;
        break;
      }
    }
  return {widths[0], widths[1], widths[2], widths[3]};
}

}  // namespace ff
