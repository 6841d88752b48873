// `flowfusion bench SEQUENCE...`: accuracy, speed and memory of the system next to the plain
// odometry and OpenCV's odometry, measured on the same frames in the same run.
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>

#include "command.h"
#include "flowfusion/core/error.h"
#include "flowfusion/core/process_memory.h"
#include "flowfusion/core/timings.h"
#include "flowfusion/eval/bench_utils.h"
#include "flowfusion/eval/reference_odometry.h"
#include "flowfusion/eval/segmentation_metrics.h"
#include "flowfusion/eval/trajectory_metrics.h"
#include "flowfusion/io/tum_folder_source.h"
#include "flowfusion/sinks/files_sink.h"
#include "flowfusion/pipeline/run.h"
#include "sequence_options.h"

namespace fs = std::filesystem;

namespace ff::app {
namespace {

struct BenchCommand {
  std::vector<std::string> sequences;
  std::string out;
  bool no_reference = false;
  SystemOptions system;
};

// The columns of one row; NaN prints as "-".
struct Row {
  std::string sequence, method;
  size_t frames = 0;
  double ate = NAN, rpe_t = NAN, rpe_r = NAN, total_ms = NAN;
  std::vector<double> stage_ms;
  double map_ms = NAN;  // prediction + fusion, summed over the run and divided by its frames
  // The whole run's wall time divided by its frames: loading, the pipeline, writing masks and (the
  // full system) the map export after the last frame.
  double end_to_end_ms = NAN;
  double export_ms = NAN;  // the map export alone (once per run)
  double iou = NAN, precision = NAN, recall = NAN, peak_mib = NAN;
  // Share of the pixels marked dynamic (mean over frames, %) and the frames with over 5 % marked:
  // on a static sequence every mark is false (eval static).
  double marked_percent = NAN, frames_above = NAN;
};

const std::vector<std::string> kStages = {"odometry", "flow", "consensus", "clustering", "scores", "prediction", "fusion"};

void addTrajectoryErrors(Row& row, const TumSequence& seq, const Trajectory& est) {
  if (!seq.groundtruth()) return;
  row.ate = eval::computeAte(*seq.groundtruth(), est).translation_m.rmse;
  try {
    const auto rpe = eval::computeRpe(*seq.groundtruth(), est);
    row.rpe_t = rpe.translation_rmse_m_per_s;
    row.rpe_r = rpe.rotation_rmse_deg_per_s;
  } catch (const InputError&) {
    // Shorter than the 1 s RPE interval: no RPE to report.
  }
}

Row runOurs(const TumSequence& seq, const std::string& label, const std::string& method, SystemConfig config,
            const BenchCommand& c, const fs::path& out_root) {
  FilesSinkOptions o;
  o.out_dir = (out_root / label / method).string();
  o.overwrite = true;
  o.export_map = config.pipeline.fusion;
  o.write_clusters = config.pipeline.cluster_log;
  FilesSink files(o);
  const auto start = std::chrono::steady_clock::now();
  TumFolderSource source(seq, c.system.frames.empty() ? FrameRange{} : parseFrameRange(c.system.frames));
  const RunSummary s = runSequence(source, config, {&files});
  const double wall_ms = msSince(start);
  Row row;
  row.sequence = label;
  row.method = method;
  row.frames = s.frames;
  addTrajectoryErrors(row, seq, s.trajectory);
  row.total_ms = s.frame_ms_median;
  if (s.frames > 0) row.end_to_end_ms = wall_ms / static_cast<double>(s.frames);
  if (o.export_map) row.export_ms = s.export_ms;
  for (const auto& stage : kStages)
    row.stage_ms.push_back(s.timings.samples(stage).empty() ? NAN : s.timings.medianMs(stage));
  if (config.pipeline.fusion && s.frames > 0) {
    double sum = 0;
    for (const char* stage : {"prediction", "fusion"})
      for (double ms : s.timings.samples(stage)) sum += ms;
    row.map_ms = sum / static_cast<double>(s.frames);
  }
  const std::string masks = (fs::path(o.out_dir) / "masks").string();
  if (const auto gt_masks = seq.masksDir(); gt_masks && config.pipeline.segmentation) {
    const auto seg = eval::evaluateSegmentation(*gt_masks, masks);
    row.iou = seg.mean_iou;
    row.precision = seg.mean_precision;
    row.recall = seg.mean_recall;
  }
  if (config.pipeline.segmentation && s.frames > 0) {
    const auto marks = eval::evaluateStaticMasks(masks);
    row.marked_percent = 100 * marks.mean_marked;
    row.frames_above = static_cast<double>(marks.frames_above);
  }
  row.peak_mib = peakResidentMiB();
  return row;
}

Row runReference(const TumSequence& seq, const std::string& label, eval::ReferenceMethod method,
                 const BenchCommand& c) {
  std::optional<size_t> max_frames;
  if (!c.system.frames.empty()) {
    const FrameRange r = parseFrameRange(c.system.frames);
    if (r.first != 0) throw InputError("bench: --frames must start at 0 when the OpenCV columns run (or pass --no-reference)");
    if (r.last >= 0) max_frames = static_cast<size_t>(r.last) + 1;
  }
  const auto start = std::chrono::steady_clock::now();
  const eval::ReferenceRun run = eval::runReferenceOdometry(method, seq, max_frames);
  const double wall_ms = msSince(start);
  Row row;
  row.sequence = label;
  row.method = eval::methodName(method);
  row.frames = run.trajectory.size();
  addTrajectoryErrors(row, seq, run.trajectory);
  row.total_ms = run.median_ms;
  if (!run.trajectory.empty()) row.end_to_end_ms = wall_ms / static_cast<double>(run.trajectory.size());
  row.stage_ms.assign(kStages.size(), NAN);
  row.stage_ms[0] = run.median_ms;
  row.peak_mib = peakResidentMiB();
  return row;
}

// The masks' figures over the sequences at once, as a change is judged on a scene set
// (docs/scenes.md): mean mIoU, precision and recall of the rows with true masks, mean marked share
// of those without (static sequences, where every mark is false).
void printMaskMeans(const std::vector<Row>& rows) {
  double iou = 0, precision = 0, recall = 0, marked = 0;
  int with_masks = 0, without = 0;
  for (const Row& r : rows) {
    if (!std::isnan(r.iou)) {
      iou += r.iou;
      precision += r.precision;
      recall += r.recall;
      ++with_masks;
    } else if (!std::isnan(r.marked_percent)) {
      marked += r.marked_percent;
      ++without;
    }
  }
  if (with_masks > 1)
    std::printf("mean of the %d sequences with true masks: mIoU %.3f, precision %.3f, recall %.3f\n", with_masks,
                iou / with_masks, precision / with_masks, recall / with_masks);
  if (without > 1) std::printf("mean of the %d sequences without: marked %.2f %%\n", without, marked / without);
}

void execute(const BenchCommand& c) {
  const SystemConfig config = c.system.systemConfig();
  const bool keep = !c.out.empty();
  const fs::path out_root = keep ? fs::path(c.out) : fs::temp_directory_path() / ("flowfusion_bench_" + std::to_string(getpid()));
  if (keep) prepareOutputDir(c.out, false);
  std::vector<Row> rows;
  for (const auto& dir : c.sequences) {
    const TumSequence seq = TumSequence::open(dir, c.system.sequenceOptions());
    const std::string label = fs::path(dir).filename().empty() ? fs::path(dir).parent_path().filename().string()
                                                               : fs::path(dir).filename().string();
    std::fprintf(stderr, "bench: %s ...\n", label.c_str());
    rows.push_back(runOurs(seq, label, "flowfusion", config, c, out_root));
    SystemConfig plain = config;
    plain.pipeline.segmentation = false;
    plain.pipeline.fusion = false;
    if (plain.pipeline.tracking == TrackingMode::FrameToModel) plain.pipeline.tracking = TrackingMode::FrameToKeyframe;
    rows.push_back(runOurs(seq, label, "odometry-only", plain, c, out_root));
    if (!c.no_reference) {
      rows.push_back(runReference(seq, label, eval::ReferenceMethod::RgbdOdometry, c));
      rows.push_back(runReference(seq, label, eval::ReferenceMethod::RgbdIcpOdometry, c));
    }
  }
  if (!keep) fs::remove_all(out_root);

  std::vector<std::string> headers = {"sequence", "method", "frames", "ATE_m", "RPE_m/s", "RPE_deg/s", "ms/frame", "fps"};
  for (const auto& s : kStages) headers.push_back(s + "_ms");
  headers.push_back("map_ms_mean");
  headers.push_back("e2e_ms");
  headers.push_back("export_ms");
  for (const char* h : {"mIoU", "precision", "recall", "marked_%", "frames>5%", "peak_MiB"}) headers.push_back(h);
  eval::TextTable table(headers);
  using T = eval::TextTable;
  for (const Row& r : rows) {
    std::vector<std::string> cells = {r.sequence, r.method, std::to_string(r.frames), T::num(r.ate, 4), T::num(r.rpe_t, 4),
                                      T::num(r.rpe_r, 3), T::num(r.total_ms, 1), T::num(1000.0 / r.total_ms, 1)};
    for (double ms : r.stage_ms) cells.push_back(T::num(ms, 1));
    cells.push_back(T::num(r.map_ms, 1));
    cells.push_back(T::num(r.end_to_end_ms, 1));
    cells.push_back(T::num(r.export_ms, 0));
    for (double v : {r.iou, r.precision, r.recall}) cells.push_back(T::num(v, 3));
    cells.push_back(T::num(r.marked_percent, 2));
    cells.push_back(T::num(r.frames_above, 0));
    cells.push_back(T::num(r.peak_mib, 0));
    table.addRow(cells);
  }
  std::printf("%s", table.str().c_str());
  printMaskMeans(rows);
  std::printf("ms columns: medians over the frames that ran the stage, wall time, %d threads. ms/frame: whole pipeline\n"
              "without image loading, wall time (the flow beside the odometry and the fusion beside the next frame's\n"
              "tracking count once; their own columns are their own durations). map_ms_mean: prediction + fusion\n"
              "per frame on average (fusion runs every pipeline.fusion_every-th frame). e2e_ms: the whole run's wall\n"
              "time per frame (loading, pipeline, writing masks, the map export amortised; OpenCV rows: loading and\n"
              "odometry). export_ms: map.ply, map_points.ply and previews after the last frame, once.\n"
              "OpenCV rows: frame to frame, library defaults; their odometry_ms is the whole call. marked_%%: share of\n"
              "the pixels marked dynamic, mean over the frames; frames>5%%: frames with more than 5 %% marked (on a\n"
              "static sequence every mark is false, as eval static). peak_MiB: process peak resident memory so far\n"
              "(rows run in order).\n",
              cv::getNumThreads());
}

const RegisterCommand reg("3-bench", [](CLI::App& app) {
  auto c = std::make_shared<BenchCommand>();
  CLI::App* cmd = app.add_subcommand("bench", "Accuracy, speed and memory table next to OpenCV's odometry");
  cmd->add_option("sequences", c->sequences, "Sequence folders (TUM layout)")->required();
  cmd->add_option("--out", c->out, "Keep each run's outputs in this new folder");
  cmd->add_flag("--no-reference", c->no_reference, "Skip the OpenCV odometry rows");
  c->system.addTo(cmd);
  cmd->callback([c]() { execute(*c); });
});

}  // namespace
}  // namespace ff::app
