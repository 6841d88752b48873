// `flowfusion report RUN_DIR [--sequence SEQ]`: writes RUN_DIR/report.html, one self-contained
// page with the run's figures, trajectory, timings, masks and an interactive 3D map.
#include <cstdio>
#include <filesystem>
#include <memory>

#include "command.h"
#include "flowfusion/report/report.h"

namespace ff::app {
namespace {

void execute(const report::ReportOptions& o) {
  const std::string path = report::writeReport(o);
  std::printf("wrote %s (%.1f MB)\n", path.c_str(), std::filesystem::file_size(path) / 1e6);
}

const RegisterCommand reg("55-report", [](CLI::App& app) {
  auto o = std::make_shared<report::ReportOptions>();
  CLI::App* cmd = app.add_subcommand("report", "Write RUN_DIR/report.html: one self-contained page (opens offline) "
                                               "with the run's figures, trajectory, timings, masks and 3D map");
  cmd->add_option("RUN_DIR", o->run_dir, "Folder written by `flowfusion run --out`")->required();
  cmd->add_option("--sequence", o->sequence,
                  "The run's TUM sequence folder (colour frames, groundtruth.txt, masks/); default: the one "
                  "summary.json names, when it exists");
  cmd->add_option("--max-points", o->max_map_points, "Most map points in the 3D view")->capture_default_str();
  cmd->callback([o] { execute(*o); });
});

}  // namespace
}  // namespace ff::app
