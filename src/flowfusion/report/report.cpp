#include "flowfusion/report/report.h"

#include <filesystem>
#include <map>

#include "flowfusion/core/atomic_file.h"
#include "flowfusion/core/config.h"
#include "flowfusion/core/error.h"
#include "flowfusion/eval/segmentation_metrics.h"
#include "flowfusion/io/tum_sequence.h"
#include "flowfusion/report/report_parts.h"

namespace fs = std::filesystem;

namespace ff::report {
namespace {

constexpr double kMaxStampDiffS = 0.02;  // colour image / ground-truth mask to mask association

// The sequence folder to read colour images and ground truth from: the option, else the one the
// run's summary names when it still exists; "" when none.
std::string resolveSequence(const ReportOptions& o, const nlohmann::json& summary, nlohmann::json& data) {
  if (!o.sequence.empty()) {
    if (!fs::is_directory(o.sequence)) throw InputError(o.sequence + ": sequence folder does not exist");
    return o.sequence;
  }
  const std::string named = summary.value("sequence", std::string());
  if (!named.empty() && fs::exists(fs::path(named) / "rgb.txt")) {
    data["sequence_note"] = "sequence folder from summary.json";
    return named;
  }
  if (!named.empty()) data["sequence_note"] = "the sequence folder in summary.json is not here: no colour frames or ground truth (give --sequence)";
  return "";
}

// Timestamped files of a folder (<timestamp>.png), by time.
std::map<double, std::string> stampedFiles(const fs::path& dir) {
  std::map<double, std::string> files;
  if (!fs::is_directory(dir)) return files;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.path().extension() != ".png") continue;
    try {
      files.emplace(std::stod(e.path().stem().string()), e.path().string());
    } catch (const std::exception&) {
      // not a <timestamp>.png: not one of the run's per-frame files
    }
  }
  return files;
}

std::string nearest(const std::map<double, std::string>& files, double t) {
  auto it = files.lower_bound(t - kMaxStampDiffS);
  return it != files.end() && std::abs(it->first - t) < kMaxStampDiffS ? it->second : "";
}

std::vector<FilmFrame> filmFrames(const fs::path& run, const std::string& sequence) {
  std::map<double, std::string> colors;
  if (!sequence.empty())
    for (const auto& [t, name] : readFileList((fs::path(sequence) / "rgb.txt").string()))
      colors.emplace(t, (fs::path(sequence) / name).string());
  const auto gt_masks = sequence.empty() ? std::map<double, std::string>() : stampedFiles(fs::path(sequence) / "masks");
  std::vector<FilmFrame> frames;
  for (const auto& [t, path] : stampedFiles(run / "masks")) frames.push_back({t, path, nearest(colors, t), nearest(gt_masks, t)});
  return frames;
}

nlohmann::json headlineFromSummary(const nlohmann::json& summary) {
  nlohmann::json h;
  for (const char* key : {"frames", "complete", "stop_reason", "tracking_failures", "flow_restarts", "mean_rounds",
                          "peak_memory_mib", "map_surfels", "map_budget_reached", "load_ms_median", "notes"})
    if (summary.contains(key)) h[key] = summary[key];
  return h;
}

void addSegmentation(const fs::path& run, const std::string& sequence, nlohmann::json& headline) {
  if (sequence.empty() || !fs::is_directory(fs::path(sequence) / "masks") || !fs::is_directory(run / "masks")) return;
  const auto seg = eval::evaluateSegmentation((fs::path(sequence) / "masks").string(), (run / "masks").string());
  headline["mean_iou"] = seg.mean_iou;
  headline["mean_precision"] = seg.mean_precision;
  headline["mean_recall"] = seg.mean_recall;
  headline["seg_frames"] = seg.frames;
}

// The run's summary.json (an empty object when there is none); InputError unless it is an object.
nlohmann::json readSummary(const fs::path& path) {
  if (!fs::exists(path)) return nlohmann::json::object();
  nlohmann::json summary = readJsonFile(path.string());
  if (!summary.is_object())
    throw InputError(path.string() + ": expected a JSON object (the summary `flowfusion run` writes), got " +
                     summary.type_name());
  return summary;
}

// What the page says is missing, for the command to say too.
std::vector<std::string> missingParts(const nlohmann::json& summary, const nlohmann::json& headline,
                                      const std::string& sequence, bool has_gt) {
  std::vector<std::string> notes;
  const std::string named = summary.value("sequence", std::string());
  if (sequence.empty() && !named.empty())
    notes.push_back("the sequence folder summary.json names (" + named +
                    ") is not here: no colour frames or ground truth (give --sequence)");
  if (!sequence.empty() && !has_gt) notes.push_back(sequence + " holds no groundtruth.txt: no trajectory error");
  if (headline.contains("ate_note")) notes.push_back(headline["ate_note"].get<std::string>() + ": no trajectory error");
  return notes;
}

}  // namespace

std::string writeReport(const ReportOptions& o, std::vector<std::string>* notes) {
  const fs::path run(o.run_dir);
  if (!fs::is_directory(run)) throw InputError(o.run_dir + ": run folder does not exist");
  const fs::path traj_path = run / "trajectory.txt";
  if (!fs::exists(traj_path))
    throw InputError(traj_path.string() + " is missing: give the folder `flowfusion run --out` wrote");
  const nlohmann::json summary = readSummary(run / "summary.json");
  nlohmann::json data;
  data["run_dir"] = fs::absolute(run).lexically_normal().string();
  const std::string sequence = resolveSequence(o, summary, data);
  data["sequence"] = sequence.empty() ? summary.value("sequence", std::string()) : sequence;
  nlohmann::json headline = headlineFromSummary(summary);
  data["stage_summary"] = summary.value("timings", nlohmann::json::object());

  const Trajectory est = readTrajectory(traj_path.string());
  std::optional<Trajectory> gt;
  if (!sequence.empty() && fs::exists(fs::path(sequence) / "groundtruth.txt"))
    gt = readTrajectory((fs::path(sequence) / "groundtruth.txt").string());
  const TrajectorySection traj = trajectorySection(est, gt, o.rpe_delta_s, headline);
  data["trajectory"] = traj.json;
  addSegmentation(run, sequence, headline);

  if (fs::exists(run / "timings.csv")) data["timings"] = timingSection((run / "timings.csv").string());
  if (fs::exists(run / "config.json")) data["config"] = readJsonFile((run / "config.json").string()).dump(2);
  data["filmstrip"] = filmstripSection(filmFrames(run, sequence), o.even_frames, o.largest_frames, o.thumb_width_px,
                                       o.large_width_px);
  if (fs::exists(run / "map_points.ply")) {
    std::vector<Eigen::Vector3d> gt_in_map;
    if (traj.aligned)
      for (const auto& p : traj.json["gt"]) gt_in_map.push_back(traj.T_gt_est.inverse() * Eigen::Vector3d(p[0].get<double>(), p[1].get<double>(), p[2].get<double>()));
    data["map"] = mapSection((run / "map_points.ply").string(), o.max_map_points, est, gt_in_map);
  }
  data["headline"] = headline;
  if (notes) *notes = missingParts(summary, headline, sequence, gt.has_value());
  const std::string path = (run / "report.html").string();
  writeFileAtomic(path, renderPage(data), "report");
  return path;
}

}  // namespace ff::report
