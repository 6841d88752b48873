// The filmstrip section: mask overlays at evenly spaced frames and at the largest dynamic areas.
#include <algorithm>
#include <numeric>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "flowfusion/core/image_file.h"
#include "flowfusion/eval/segmentation_metrics.h"
#include "flowfusion/report/report_parts.h"
#include "flowfusion/visualization/overlay.h"

namespace ff::report {
namespace {

constexpr int kJpegQuality = 82;

std::string jpegDataUrl(const cv::Mat& bgr, int max_width_px) {
  cv::Mat scaled = bgr;
  if (bgr.cols > max_width_px) {
    const double f = static_cast<double>(max_width_px) / bgr.cols;
    cv::resize(bgr, scaled, cv::Size(), f, f, cv::INTER_AREA);
  }
  std::vector<uchar> bytes;
  cv::imencode(".jpg", scaled, bytes, {cv::IMWRITE_JPEG_QUALITY, kJpegQuality});
  return "data:image/jpeg;base64," + base64({reinterpret_cast<const char*>(bytes.data()), bytes.size()});
}

cv::Mat readMask(const std::string& path) { return readImageFile(path, cv::IMREAD_GRAYSCALE, "mask"); }

// The mask over the colour frame, or over grey when the colour frame is not known or not there
// (a --sequence whose rgb.txt names images it does not hold).
cv::Mat overlay(const std::string& color_path, const cv::Mat& mask) {
  cv::Mat color;
  if (!color_path.empty()) color = readImageFile(color_path, cv::IMREAD_COLOR, "colour image");
  if (color.empty()) color = cv::Mat(mask.size(), CV_8UC3, cv::Scalar(96, 96, 96));
  cv::Mat m = mask;
  if (m.size() != color.size()) cv::resize(mask, m, color.size(), 0, 0, cv::INTER_NEAREST);
  return overlayMask(color, m > 127);
}

// Indices of `even` frames spread over [0, n) and then of the `largest` other frames by area.
std::vector<std::pair<size_t, const char*>> pickFrames(const std::vector<double>& area, int even, int largest) {
  std::vector<std::pair<size_t, const char*>> picked;
  const size_t n = area.size();
  std::vector<bool> used(n, false);
  const size_t count_even = std::min<size_t>(std::max(even, 0), n);
  for (size_t k = 0; k < count_even; ++k) {
    const size_t i = count_even == 1 ? 0 : k * (n - 1) / (count_even - 1);
    if (!used[i]) picked.emplace_back(i, "evenly spaced");
    used[i] = true;
  }
  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return area[a] > area[b]; });
  int added = 0;
  for (size_t i : order) {
    if (added >= largest || area[i] <= 0) break;
    if (used[i]) continue;
    picked.emplace_back(i, "largest dynamic area");
    used[i] = true;
    ++added;
  }
  return picked;
}

}  // namespace

nlohmann::json filmstripSection(const std::vector<FilmFrame>& frames, int even, int largest, int thumb_width_px,
                                int large_width_px) {
  std::vector<double> area(frames.size());
  for (size_t i = 0; i < frames.size(); ++i) {
    const cv::Mat mask = readMask(frames[i].mask_path);
    area[i] = static_cast<double>(cv::countNonZero(mask > 127)) / std::max(1, mask.rows * mask.cols);
  }
  nlohmann::json out = nlohmann::json::array();
  for (const auto& [i, why] : pickFrames(area, even, largest)) {
    const FilmFrame& f = frames[i];
    const cv::Mat mask = readMask(f.mask_path);
    const cv::Mat est = overlay(f.color_path, mask);
    nlohmann::json e = {{"index", i}, {"timestamp", f.timestamp}, {"why", why}, {"area", area[i]},
                        {"thumb", jpegDataUrl(est, thumb_width_px)}, {"large", jpegDataUrl(est, large_width_px)}};
    if (!f.gt_mask_path.empty()) {
      const cv::Mat gt = readMask(f.gt_mask_path);
      e["gt"] = jpegDataUrl(overlay(f.color_path, gt), large_width_px);
      if (gt.size() == mask.size()) e["iou"] = eval::compareMasks(gt > 127, mask > 127).iou;
    }
    out.push_back(std::move(e));
  }
  return out;
}

}  // namespace ff::report
