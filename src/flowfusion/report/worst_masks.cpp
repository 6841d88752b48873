#include "flowfusion/report/worst_masks.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "flowfusion/core/error.h"
#include "flowfusion/core/image_file.h"
#include "flowfusion/io/tum_sequence.h"
#include "flowfusion/visualization/mask_sheet.h"

namespace ff::report {
namespace {

namespace fs = std::filesystem;

constexpr double kColorStampS = 0.02;  // mask to colour image, as the masks' own association
constexpr double kDepthStampS = 0.05;  // mask to depth image (TUM's lie up to 20 ms from the colour)

using FileList = std::vector<std::pair<double, std::string>>;

// The file of `list` nearest in time to t, within max_diff_s; throws naming the list otherwise.
std::string nearestFile(const FileList& list, const fs::path& dir, const std::string& list_name, double t,
                        double max_diff_s) {
  const auto it = std::min_element(list.begin(), list.end(), [t](const auto& a, const auto& b) {
    return std::abs(a.first - t) < std::abs(b.first - t);
  });
  if (it == list.end() || !(std::abs(it->first - t) <= max_diff_s)) {
    char stamp[32];
    std::snprintf(stamp, sizeof stamp, "%.6f", t);
    throw InputError((dir / list_name).string() + ": no image within " + std::to_string(max_diff_s) + " s of " +
                     stamp + " s");
  }
  return (dir / it->second).string();
}

cv::Mat readImage(const std::string& path, int flags, const std::string& what) {
  cv::Mat image = readImageFile(path, flags, what);
  if (image.empty()) throw InputError(path + ": cannot read the " + what);
  return image;
}

cv::Mat readMask(const std::string& path, cv::Size size) {
  cv::Mat mask = eval::readMaskFile(path);
  if (mask.size() != size) throw InputError(path + ": the mask's size differs from its colour image's");
  return mask;
}

MaskSheetRow sheetRow(const fs::path& dir, const FileList& colors, const FileList& depths,
                      const eval::FrameMaskScores& f, double depth_scale) {
  const std::string color_path = nearestFile(colors, dir, "rgb.txt", f.timestamp, kColorStampS);
  const std::string depth_path = nearestFile(depths, dir, "depth.txt", f.timestamp, kDepthStampS);
  MaskSheetRow row;
  row.color = readImage(color_path, cv::IMREAD_COLOR, "colour image");
  const cv::Mat raw = readImage(depth_path, cv::IMREAD_ANYDEPTH, "depth image");
  if (raw.type() != CV_16UC1 || raw.size() != row.color.size())
    throw InputError(depth_path + ": depth must be 16-bit, single channel, of the colour image's size");
  raw.convertTo(row.depth, CV_32F, 1.0 / depth_scale);
  row.gt_mask = readMask(f.gt_path, row.color.size());
  row.est_mask = readMask(f.est_path, row.color.size());
  char label[96];
  std::snprintf(label, sizeof label, "%.3f s\nIoU %.2f  P %.2f  R %.2f\n%lld px wrong", f.timestamp, f.scores.iou,
                f.scores.precision, f.scores.recall,
                static_cast<long long>(f.scores.false_positive + f.scores.false_negative));
  row.label = label;
  return row;
}

}  // namespace

cv::Mat worstMaskSheet(const std::string& sequence_dir, const eval::SegmentationResult& result,
                       const WorstMasksOptions& options) {
  if (options.rows < 1) throw InputError("mask sheet: at least one row is needed");
  if (!(options.depth_scale > 0)) throw InputError("mask sheet: the depth scale must be positive");
  std::vector<const eval::FrameMaskScores*> frames;
  for (const auto& f : result.per_frame)
    if (std::isfinite(f.timestamp)) frames.push_back(&f);
  if (frames.empty()) throw InputError("mask sheet: no mask is named by a timestamp, so no frame can be found");
  const auto badness = [by = options.by](const eval::FrameMaskScores* f) {
    return by == WorstBy::kIou ? -f->scores.iou
                               : static_cast<double>(f->scores.false_positive + f->scores.false_negative);
  };
  std::stable_sort(frames.begin(), frames.end(),
                   [&](const auto* a, const auto* b) { return badness(a) > badness(b); });
  frames.resize(std::min<size_t>(frames.size(), options.rows));
  const fs::path dir(sequence_dir);
  const FileList colors = readFileList((dir / "rgb.txt").string());
  const FileList depths = readFileList((dir / "depth.txt").string());
  std::vector<MaskSheetRow> rows;
  for (const auto* f : frames) rows.push_back(sheetRow(dir, colors, depths, *f, options.depth_scale));
  return maskContactSheet(rows, options.column_width_px);
}

}  // namespace ff::report
