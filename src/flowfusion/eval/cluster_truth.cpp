#include "flowfusion/eval/cluster_truth.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "flowfusion/core/error.h"
#include "flowfusion/core/image_file.h"
#include "flowfusion/eval/segmentation_metrics.h"
#include "flowfusion/eval/trajectory_metrics.h"

namespace ff::eval {

namespace fs = std::filesystem;

namespace {

// Per label value of the 16-bit label image (cluster + 1): pixels, and pixels the truth marks.
struct LabelCounts {
  std::vector<int> pixels, truth;
};
LabelCounts countLabels(const cv::Mat& labels, const cv::Mat& truth) {
  LabelCounts c{std::vector<int>(65536, 0), std::vector<int>(65536, 0)};
  for (int v = 0; v < labels.rows; ++v) {
    const uint16_t* l = labels.ptr<uint16_t>(v);
    const uint8_t* t = truth.ptr<uint8_t>(v);
    for (int u = 0; u < labels.cols; ++u) {
      ++c.pixels[l[u]];
      c.truth[l[u]] += t[u] > 127;
    }
  }
  return c;
}

ClusterVerdict verdictOf(double truth_share, double b) {
  const bool dynamic = b > 0.5;
  if (truth_share >= 0.5) return dynamic ? ClusterVerdict::kHit : ClusterVerdict::kMissed;
  return dynamic ? ClusterVerdict::kFalse : ClusterVerdict::kStatic;
}

// The column index of `name` in a CSV header.
size_t columnOf(const std::string& header, const std::string& name, const std::string& path) {
  std::istringstream in(header);
  std::string field;
  for (size_t i = 0; std::getline(in, field, ','); ++i)
    if (field == name) return i;
  throw InputError(path + ": the header has no column '" + name + "' (not a cluster log of run --cluster-log?)");
}

std::string fieldAt(const std::string& row, size_t index) {
  std::istringstream in(row);
  std::string field;
  for (size_t i = 0; std::getline(in, field, ','); ++i)
    if (i == index) return field;
  return {};
}

// The rows of one log, `counts` its label image's against the truth.
void readLog(const std::string& path, const LabelCounts& counts, int frame, double timestamp, ClusterTruth& out) {
  std::ifstream in(path);
  std::string header, row;
  if (!std::getline(in, header)) throw InputError(path + ": empty cluster log");
  if (out.header.empty()) out.header = header;
  if (header != out.header) throw InputError(path + ": its columns differ from the other logs'");
  const size_t b_column = columnOf(header, "b", path);
  for (int line = 2; std::getline(in, row); ++line) {
    char* end_id = nullptr;
    char* end_b = nullptr;
    const std::string id_text = fieldAt(row, 0), b_text = fieldAt(row, b_column);
    const long id = std::strtol(id_text.c_str(), &end_id, 10);
    const double b = std::strtod(b_text.c_str(), &end_b);
    if (id_text.empty() || *end_id != '\0' || id < 0 || id >= 65535 || b_text.empty() || *end_b != '\0')
      throw InputError(path + ":" + std::to_string(line) + ": not a cluster row");
    const int pixels = counts.pixels[id + 1];
    const double share = pixels > 0 ? static_cast<double>(counts.truth[id + 1]) / pixels
                                    : std::numeric_limits<double>::quiet_NaN();
    out.rows.push_back({frame, timestamp, row, share, b, verdictOf(share, b)});
  }
}

}  // namespace

const char* verdictName(ClusterVerdict v) {
  switch (v) {
    case ClusterVerdict::kHit: return "hit";
    case ClusterVerdict::kMissed: return "missed";
    case ClusterVerdict::kFalse: return "false";
    case ClusterVerdict::kStatic: return "static";
  }
  return "static";
}

ClusterTruth clusterTruth(const std::string& gt_dir, const std::string& clusters_dir) {
  for (const std::string& dir : {gt_dir, clusters_dir})
    if (!fs::is_directory(dir)) throw InputError(dir + ": folder does not exist");
  const auto logs = stampedFiles(clusters_dir, ".csv");
  if (logs.empty()) throw InputError(clusters_dir + ": no cluster log (<timestamp>.csv; run --cluster-log writes them)");
  const auto masks = stampedFiles(gt_dir, ".png");
  std::vector<double> log_t, mask_t;
  for (const auto& [t, p] : logs) log_t.push_back(t);
  for (const auto& [t, p] : masks) mask_t.push_back(t);
  ClusterTruth out;
  for (const auto& [i, j] : associateStamps(log_t, mask_t, kMaxMaskStampDiffS)) {
    const std::string labels_path = fs::path(logs[i].second).replace_extension(".png").string();
    if (!fs::exists(labels_path)) throw InputError(labels_path + ": the cluster log's label image is missing");
    const cv::Mat labels = readImageFile(labels_path, cv::IMREAD_UNCHANGED, "cluster labels");
    const cv::Mat truth = readMaskFile(masks[j].second);
    if (labels.type() != CV_16UC1 || labels.size() != truth.size())
      throw InputError(labels_path + ": not a 16-bit label image of the size of " + masks[j].second);
    readLog(logs[i].second, countLabels(labels, truth), static_cast<int>(j), log_t[i], out);
  }
  if (out.rows.empty() && out.header.empty())
    throw InputError(clusters_dir + ": no cluster log has a true mask in " + gt_dir + " (within 0.02 s)");
  std::stable_sort(out.rows.begin(), out.rows.end(),
                   [](const ClusterTruthRow& a, const ClusterTruthRow& b) { return a.frame < b.frame; });
  return out;
}

std::string clusterTruthCsv(const ClusterTruth& truth, int first, int last, bool all) {
  std::string out = "frame,timestamp," + truth.header + ",truth_share,verdict\n";
  char prefix[64], suffix[64];
  for (const ClusterTruthRow& r : truth.rows) {
    if (r.frame < first || r.frame > last || (!all && r.verdict == ClusterVerdict::kStatic)) continue;
    std::snprintf(prefix, sizeof prefix, "%d,%.6f,", r.frame, r.timestamp);
    if (std::isfinite(r.truth_share))
      std::snprintf(suffix, sizeof suffix, ",%.3f,%s\n", r.truth_share, verdictName(r.verdict));
    else
      std::snprintf(suffix, sizeof suffix, ",nan,%s\n", verdictName(r.verdict));
    out += prefix + r.record + suffix;
  }
  return out;
}

}  // namespace ff::eval
