// `flowfusion run SEQUENCE --out DIR`: the whole system on one sequence.
#include <unistd.h>

#include <cstdio>
#include <iostream>

#include "command.h"
#include "flowfusion/eval/bench_utils.h"
#include "flowfusion/eval/trajectory_metrics.h"
#include "flowfusion/pipeline/run_sequence.h"
#include "sequence_options.h"

namespace ff::app {
namespace {

struct RunCommand {
  std::string sequence, out;
  bool overwrite = false, overlays = false, no_map = false, quiet = false;
  SystemOptions system;
};

void execute(const RunCommand& c) {
  const TumSequence seq = TumSequence::open(c.sequence, c.system.sequenceOptions());
  const SystemConfig config = c.system.systemConfig();
  RunOptions o;
  o.out_dir = c.out;
  o.overwrite = c.overwrite;
  if (!c.system.frames.empty()) o.frames = parseFrameRange(c.system.frames);
  o.write_overlays = c.overlays;
  o.export_map = !c.no_map;
  const bool tty = isatty(fileno(stderr));
  if (!c.quiet && tty)
    o.progress = [](size_t done, size_t total) {
      if (done == total || done % 10 == 0) std::fprintf(stderr, "\rframe %zu/%zu", done, total);
      if (done == total) std::fprintf(stderr, "\n");
    };
  const RunSummary s = runSequence(seq, config, o);
  if (c.quiet) return;
  std::printf("frames %zu, tracking failures %d, flow restarts %d, median ms per frame:", s.frames,
              s.tracking_failures, s.flow_restarts);
  for (const auto& stage : s.timings.stages()) std::printf(" %s %.1f", stage.c_str(), s.timings.medianMs(stage));
  std::printf(" (mean total %.1f ms)\n", eval::mean(s.timings.frameTotals()));
  if (seq.groundtruth()) {
    const auto ate = eval::computeAte(*seq.groundtruth(), s.trajectory);
    std::printf("ATE RMSE %.4f m over %zu poses (ground truth in the sequence folder)\n", ate.translation_m.rmse,
                ate.matched_poses);
  }
  std::printf("map: %zu surfels%s; peak memory %.0f MiB\n", s.map_surfels,
              s.map_budget_reached ? " (budget reached: raise fusion.max_surfels for more)" : "", s.peak_memory_mib);
  std::printf("wrote:");
  for (const auto& w : s.written) std::printf(" %s", w.c_str());
  std::printf("\n");
}

const RegisterCommand reg("1-run", [](CLI::App& app) {
  auto c = std::make_shared<RunCommand>();
  CLI::App* cmd = app.add_subcommand("run", "Track a TUM-layout RGB-D sequence, segment moving objects, map the static scene");
  cmd->add_option("sequence", c->sequence, "Sequence folder (rgb.txt, depth.txt, rgb/, depth/)")->required();
  cmd->add_option("--out", c->out, "Output folder (trajectory.txt, masks/, map.ply, ...)")->required();
  cmd->add_flag("--overwrite", c->overwrite, "Write into a non-empty output folder");
  cmd->add_flag("--overlays", c->overlays, "Also write overlays/<timestamp>.png (dynamic pixels in red)");
  cmd->add_flag("--no-map", c->no_map, "Skip map.ply, map_points.ply and preview/");
  cmd->add_flag("--quiet", c->quiet, "Print nothing on success");
  c->system.addTo(cmd);
  cmd->callback([c]() { execute(*c); });
});

}  // namespace
}  // namespace ff::app
