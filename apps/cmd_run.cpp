// `flowfusion run SEQUENCE --out DIR`: frames from a source, through the system, to the files
// sink (and a progress line). SIGINT/SIGTERM stop it after the current frame with an honest,
// marked partial result. `--realtime [--rate R]` replays the recording as a live camera
// (io/realtime_replay.h): the frames the system is too slow for are dropped, and the run reports
// what it processed, dropped and the latency.
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <sstream>

#include "command.h"
#include "flowfusion/core/error.h"
#include "flowfusion/core/output_folder.h"
#include "flowfusion/eval/trajectory_metrics.h"
#include "flowfusion/io/realtime_replay.h"
#include "flowfusion/sinks/files_sink.h"
#include "flowfusion/sinks/mcap_sink.h"
#include "flowfusion/pipeline/run.h"
#include "flowfusion/sinks/report_sink.h"
#include "flowfusion/sinks/tracked_trajectory_sink.h"
#include "flowfusion/sinks/viewer_sink.h"
#include "sequence_options.h"
#include "stop_signals.h"

namespace ff::app {
namespace {

// "offered 120, processed 80, dropped 40 (33 %), latency p50 35.1 ms, p95 60.2 ms".
std::string liveLine(const LiveFigures& f) {
  const double dropped_percent =
      f.frames_offered > 0 ? 100.0 * static_cast<double>(f.frames_dropped) / static_cast<double>(f.frames_offered) : 0;
  char line[160];
  std::snprintf(line, sizeof line, "offered %zu, processed %zu, dropped %zu (%.0f %%), latency p50 %.1f ms, p95 %.1f ms",
                f.frames_offered, f.frames_processed, f.frames_dropped, dropped_percent, f.latency_ms_p50,
                f.latency_ms_p95);
  return line;
}

// "frame N/M" on a terminal; a live run's figures instead (RunInfo::live).
class ProgressSink : public ResultSink {
 public:
  void begin(const RunInfo& info) override {
    total_ = info.expected_frames.value_or(0);
    live_ = info.live;
  }
  void frame(const RgbdFrame&, const FrameResult&) override {
    ++done_;
    if (done_ % 10 != 0 && done_ != total_) return;
    if (live_)
      std::fprintf(stderr, "\r%s   ", liveLine(*live_).c_str());
    else
      std::fprintf(stderr, "\rframe %zu/%zu", done_, total_);
  }
  void end(RunSummary&, const StaticMap*) override { std::fprintf(stderr, "\n"); }

 private:
  size_t done_ = 0, total_ = 0;
  const LiveFigures* live_ = nullptr;
};

struct RunCommand {
  std::string sequence, out, mcap, map_in;
  bool overwrite = false, overlays = false, cluster_log = false, no_map = false, quiet = false, report = false,
       show = false;
  bool realtime = false;
  double rate = 1.0;  // --rate: times the recorded speed
  SystemOptions system;
};

// --rate as a RealtimeReplay takes it: a positive, finite factor.
void checkRate(double rate) {
  if (std::isfinite(rate) && rate > 0) return;
  std::ostringstream got;
  got << rate;
  throw InputError("--rate must be a positive, finite factor of the recorded speed (e.g. 0.5, 1, 2), got " +
                   got.str());
}

void printSummary(const RunSummary& s, const FrameSource& source) {
  std::printf("frames %zu, tracking failures %d, flow restarts %d, loop closures %d (%d corrections, %d keyframes), median ms per frame:",
              s.frames, s.tracking_failures, s.flow_restarts, s.loop_closures, s.loop_corrections, s.slam_keyframes);
  for (const auto& stage : s.timings.stages()) std::printf(" %s %.1f", stage.c_str(), s.timings.medianMs(stage));
  std::printf(" (frame %.1f ms wall, overlapping stages counted once)\n", s.frame_ms_median);
  if (source.groundtruth()) {
    try {
      const auto ate = eval::computeAte(*source.groundtruth(), s.trajectory);
      std::printf("ATE RMSE %.4f m over %zu poses (ground truth in the sequence folder)\n", ate.translation_m.rmse,
                  ate.matched_poses);
      if (s.map_in)  // in the saved map's world frame, which its run took from the ground truth
        std::printf("ATE RMSE without alignment %.4f m\n",
                    eval::computeAte(*source.groundtruth(), s.trajectory, 0.02, "ground truth", "trajectory",
                                     eval::AteAlignment::None)
                        .translation_m.rmse);
    } catch (const InputError& e) {
      std::printf("ATE: not computed: %s\n", e.what());  // e.g. too few poses to align
    }
  }
  if (s.live) std::printf("real time: %s\n", liveLine(*s.live).c_str());
  std::printf("map: %zu surfels%s; peak memory %.0f MiB\n", s.map_surfels,
              s.map_budget_reached ? " (budget reached: raise fusion.max_surfels for more)" : "", s.peak_memory_mib);
  if (s.lost_frames > 0) std::printf("lost %d frames, relocalized %d\n", s.lost_frames, s.relocalized_frames);
  if (const std::optional<MapReuse>& m = s.map_in; m && m->localized_at_frame >= 0)
    std::printf("continued in %s (%d keyframes, %zu surfels): localized at frame %d, %d frames before without a pose\n",
                m->path.c_str(), m->keyframes, m->surfels, m->localized_at_frame, m->unlocalized_frames);
  for (const auto& note : s.notes) std::printf("note: %s\n", note.c_str());
  std::printf("wrote:");
  for (const auto& w : s.written) std::printf(" %s", w.c_str());
  std::printf("\n");
}

void execute(const RunCommand& c) {
  if (c.realtime) checkRate(c.rate);
  SystemConfig config = c.system.systemConfig(c.realtime ? liveDefaults() : SystemConfig{});
  if (c.cluster_log) config.pipeline.cluster_log = true;
  FilesSinkOptions files;
  files.out_dir = c.out;
  files.overwrite = c.overwrite;
  files.write_overlays = c.overlays;
  files.write_clusters = config.pipeline.cluster_log;
  files.export_map = !c.no_map;
  FilesSink sink(files);
  refuseOverlap(c.out, c.sequence, "the input sequence");
  setOutputCommand("run");
  const std::unique_ptr<FrameSource> recording = c.system.openSource(c.sequence);
  // Read and checked before anything is written.
  std::optional<SavedMap> map_in;
  if (!c.map_in.empty()) map_in = readMapFor(c.map_in, c.out, recording->camera(), config.slam);
  std::optional<RealtimeReplay> replay;
  if (c.realtime) replay.emplace(*recording, c.rate);
  FrameSource& source = replay ? static_cast<FrameSource&>(*replay) : *recording;
  ProgressSink progress;
  TrackedTrajectorySink tracked(c.out);
  std::vector<ResultSink*> sinks = {&sink, &tracked};
  if (!c.quiet && isatty(fileno(stderr))) sinks.push_back(&progress);
  ViewerSink viewer;
  if (c.show) sinks.push_back(&viewer);
  report::ReportOptions report_options;
  report_options.run_dir = c.out;
  if (std::filesystem::is_directory(c.sequence)) report_options.sequence = c.sequence;
  ReportSink report(report_options);
  if (c.report) sinks.push_back(&report);  // after the files sink, whose files it reads
  std::unique_ptr<McapSink> mcap;
  if (!c.mcap.empty()) {
    refuseOverlap(c.mcap, c.sequence, "the input sequence");
    mcap = std::make_unique<McapSink>(c.mcap);
    sinks.push_back(mcap.get());
  }
  const StopSignals signals;
  RunControl control{signals.flag(), signals.reason()};
  control.map_in = map_in ? &*map_in : nullptr;
  const RunSummary s = runSequence(source, config, sinks, control);
  if (!s.complete) {
    std::fprintf(stderr, "flowfusion: run stopped after %zu frames: %s; partial results in %s (summary.json says so)\n",
                 s.frames, s.stop_reason.c_str(), c.out.c_str());
    throw ExitStatus{signals.exitStatus()};
  }
  if (!c.quiet) printSummary(s, source);
}

const RegisterCommand reg("1-run", [](CLI::App& app) {
  auto c = std::make_shared<RunCommand>();
  CLI::App* cmd =
      app.add_subcommand("run", "Track an RGB-D sequence (folder, ROS 1 or ROS 2 bag), segment moving objects, map the static scene");
  cmd->add_option("sequence", c->sequence, "Sequence folder (TUM, Bonn, ICL-NUIM, ETH3D layouts), ROS 1 .bag, or ROS 2 bag (rosbag2 folder, .mcap, .db3)")
      ->required();
  cmd->add_option("--out", c->out, "Output folder (trajectory.txt, masks/, map.ply, ...)")->required();
  cmd->add_flag("--overwrite", c->overwrite, "Write into a non-empty output folder");
  cmd->add_option("--mcap", c->mcap,
                  "Also write the run as an MCAP file for Foxglove (pose, path, colour, mask, depth, calibration, map)");
  cmd->add_flag("--overlays", c->overlays, "Also write overlays/<timestamp>.png (dynamic pixels in red)");
  cmd->add_flag("--cluster-log", c->cluster_log,
                "Also write clusters/<timestamp>.csv (each cluster's evidence and score) and .png (its pixels); "
                "nothing without segmentation. See docs/formats.md");
  cmd->add_flag("--no-map", c->no_map, "Skip map.ply, map_points.ply, preview/ and map.ffmap");
  cmd->add_option("--map-in", c->map_in,
                  "Continue in a previous run's map: its folder (or its map.ffmap). The run finds its first pose "
                  "among the map's keyframes and tracks and maps in its world frame; summary.json's map_in says "
                  "when (frames before have no pose)");
  cmd->add_flag("--quiet", c->quiet, "Print nothing on success");
  cmd->add_flag("--report", c->report, "Also write OUT/report.html (see `flowfusion report`)");
  cmd->add_flag("--show", c->show, "Show the frame with its mask, the dynamic score and the path while running");
  CLI::Option* realtime = cmd->add_flag(
      "--realtime", c->realtime,
      "Replay as a live camera: frames offered at their recorded times, those arriving while the system is busy "
      "replace the waiting one (dropped); summary.json adds frames_offered/processed/dropped and latency_ms_p50/p95");
  cmd->add_option("--rate", c->rate, "With --realtime: times the recorded speed (default 1; 2 = twice as fast)")
      ->needs(realtime);
  c->system.addTo(cmd);
  cmd->callback([c]() { execute(*c); });
});

}  // namespace
}  // namespace ff::app
