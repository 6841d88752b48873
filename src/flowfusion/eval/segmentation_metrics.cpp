#include "flowfusion/eval/segmentation_metrics.h"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "flowfusion/core/error.h"
#include "flowfusion/core/image_file.h"
#include "flowfusion/eval/trajectory_metrics.h"

namespace ff::eval {

namespace fs = std::filesystem;

namespace {

double ratioOrOne(int64_t num, int64_t den) { return den == 0 ? 1.0 : static_cast<double>(num) / den; }

struct MaskFiles {
  std::vector<std::pair<double, std::string>> stamped;  // sorted by timestamp
  std::map<std::string, std::string> named;             // stem -> path, stems that are not numbers
};

MaskFiles listMasks(const std::string& dir) {
  if (!fs::is_directory(dir)) throw InputError(dir + ": mask folder does not exist");
  MaskFiles m;
  m.stamped = stampedFiles(dir, ".png", &m.named);
  if (m.stamped.empty() && m.named.empty()) throw InputError(dir + ": no .png masks in this folder");
  return m;
}

}  // namespace

std::vector<std::pair<double, std::string>> stampedFiles(const std::string& dir, const std::string& extension,
                                                         std::map<std::string, std::string>* named) {
  std::vector<std::pair<double, std::string>> files;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (!e.is_regular_file() || e.path().extension() != extension) continue;
    const std::string stem = e.path().stem().string();
    char* end = nullptr;
    const double t = std::strtod(stem.c_str(), &end);
    if (!stem.empty() && end && *end == '\0')
      files.emplace_back(t, e.path().string());
    else if (named)
      (*named)[stem] = e.path().string();
  }
  std::sort(files.begin(), files.end());
  return files;
}

cv::Mat readMaskFile(const std::string& path) {
  const cv::Mat raw = readImageFile(path, cv::IMREAD_UNCHANGED, "mask image");
  if (raw.empty()) throw InputError(path + ": cannot read mask image");
  if (raw.depth() != CV_8U)
    throw InputError(path + ": mask must be an 8-bit image (255 = dynamic, 0 = static)");
  if (raw.channels() == 1) return raw;
  cv::Mat grey;
  cv::cvtColor(raw, grey, raw.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
  return grey;
}

MaskScores scoresFromCounts(int64_t true_positive, int64_t false_positive, int64_t false_negative) {
  MaskScores s;
  s.true_positive = true_positive;
  s.false_positive = false_positive;
  s.false_negative = false_negative;
  s.iou = ratioOrOne(true_positive, true_positive + false_positive + false_negative);
  s.precision = ratioOrOne(true_positive, true_positive + false_positive);
  s.recall = ratioOrOne(true_positive, true_positive + false_negative);
  return s;
}

MaskScores compareMasks(const cv::Mat& gt, const cv::Mat& est, const std::string& gt_name,
                        const std::string& est_name) {
  if (gt.type() != CV_8UC1) throw InputError(gt_name + ": mask must be a single-channel 8-bit image");
  if (est.type() != CV_8UC1) throw InputError(est_name + ": mask must be a single-channel 8-bit image");
  if (gt.size() != est.size())
    throw InputError(est_name + ": mask is " + std::to_string(est.cols) + "x" + std::to_string(est.rows) + " but " +
                     gt_name + " is " + std::to_string(gt.cols) + "x" + std::to_string(gt.rows));
  int64_t tp = 0, fp = 0, fn = 0;
  for (int y = 0; y < gt.rows; ++y) {
    const uint8_t* g = gt.ptr<uint8_t>(y);
    const uint8_t* e = est.ptr<uint8_t>(y);
    for (int x = 0; x < gt.cols; ++x) {
      const bool gd = g[x] > 127, ed = e[x] > 127;
      tp += gd && ed;
      fp += !gd && ed;
      fn += gd && !ed;
    }
  }
  return scoresFromCounts(tp, fp, fn);
}

SegmentationResult evaluateSegmentation(const std::string& gt_dir, const std::string& est_dir) {
  const MaskFiles gt = listMasks(gt_dir);
  const MaskFiles est = listMasks(est_dir);

  std::vector<FrameMaskScores> pairs;
  std::vector<double> gt_t, est_t;
  for (const auto& [t, p] : gt.stamped) gt_t.push_back(t);
  for (const auto& [t, p] : est.stamped) est_t.push_back(t);
  for (const auto& [i, j] : associateStamps(gt_t, est_t, kMaxMaskStampDiffS))
    pairs.push_back({gt.stamped[i].second, est.stamped[j].second, gt_t[i], {}});
  std::sort(pairs.begin(), pairs.end(), [](const auto& a, const auto& b) { return a.timestamp < b.timestamp; });
  const double no_stamp = std::numeric_limits<double>::quiet_NaN();
  for (const auto& [stem, p] : gt.named)
    if (const auto it = est.named.find(stem); it != est.named.end()) pairs.push_back({p, it->second, no_stamp, {}});
  if (pairs.empty())
    throw InputError(est_dir + ": no mask matches one in " + gt_dir +
                     " (names must be timestamps within 0.02 s of each other, or identical)");

  SegmentationResult r;
  r.frames = pairs.size();
  r.gt_unmatched = gt.stamped.size() + gt.named.size() - pairs.size();
  r.est_unmatched = est.stamped.size() + est.named.size() - pairs.size();
  int64_t tp = 0, fp = 0, fn = 0;
  double iou = 0, precision = 0, recall = 0;
  for (FrameMaskScores& pair : pairs) {
    const cv::Mat gt_mask = readMaskFile(pair.gt_path);
    pair.pixels = static_cast<int64_t>(gt_mask.total());
    const MaskScores& s = pair.scores =
        compareMasks(gt_mask, readMaskFile(pair.est_path), pair.gt_path, pair.est_path);
    tp += s.true_positive;
    fp += s.false_positive;
    fn += s.false_negative;
    iou += s.iou;
    precision += s.precision;
    recall += s.recall;
  }
  const double n = static_cast<double>(pairs.size());
  r.mean_iou = iou / n;
  r.mean_precision = precision / n;
  r.mean_recall = recall / n;
  r.pooled = scoresFromCounts(tp, fp, fn);
  r.iou_loss = iouLoss(pairs);
  r.per_frame = std::move(pairs);
  return r;
}

IouLoss iouLoss(const std::vector<FrameMaskScores>& frames, double small_mover_share) {
  IouLoss loss;
  const double n = static_cast<double>(frames.size());
  for (const FrameMaskScores& f : frames) {
    const MaskScores& s = f.scores;
    const double lost = (1.0 - s.iou) / n;
    const int64_t truth = s.true_positive + s.false_negative;
    if (truth == 0)
      loss.false_marks_without_mover += lost;
    else if (s.iou < 0.2 && 5 * s.true_positive < truth)
      (truth < small_mover_share * static_cast<double>(f.pixels) ? loss.small_mover_missed : loss.mover_missed) += lost;
    else if (s.false_positive > s.false_negative)
      loss.false_marks_over_misses += lost;
    else
      loss.mover_partly_found += lost;
  }
  return loss;
}

StaticMaskResult evaluateStaticMasks(const std::string& est_dir, double above) {
  if (!(above >= 0 && above < 1)) throw InputError("the share a frame must exceed must be in [0, 1)");
  const MaskFiles est = listMasks(est_dir);
  StaticMaskResult r;
  r.above = above;
  const auto add = [&](double t, const std::string& path) {
    const cv::Mat m = readMaskFile(path);
    const double marked = m.empty() ? 0.0 : static_cast<double>(cv::countNonZero(m > 127)) / m.total();
    r.per_frame.push_back({path, t, marked});
    r.mean_marked += marked;
    r.max_marked = std::max(r.max_marked, marked);
    r.frames_above += marked > above;
  };
  for (const auto& [t, p] : est.stamped) add(t, p);
  for (const auto& [stem, p] : est.named) add(std::numeric_limits<double>::quiet_NaN(), p);
  r.frames = r.per_frame.size();
  r.mean_marked /= static_cast<double>(r.frames);
  r.fraction_above = static_cast<double>(r.frames_above) / static_cast<double>(r.frames);
  return r;
}

}  // namespace ff::eval
