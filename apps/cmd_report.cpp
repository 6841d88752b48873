// `flowfusion report RUN_DIR [--sequence SEQ]`: writes RUN_DIR/report.html, one self-contained
// page with the run's figures, trajectory, timings, masks and an interactive 3D map.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "command.h"
#include "flowfusion/report/report.h"

namespace ff::app {
namespace {

void execute(const report::ReportOptions& o) {
  std::vector<std::string> notes;
  const std::string path = report::writeReport(o, &notes);
  for (const auto& note : notes) std::fprintf(stderr, "flowfusion: report: note: %s\n", note.c_str());
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
  auto max_points = std::make_shared<long long>(static_cast<long long>(o->max_map_points));
  cmd->add_option("--max-points", *max_points, "Most map points in the 3D view, 1 to 10000000")
      ->check(CLI::Range(1LL, 10000000LL))
      ->capture_default_str();
  cmd->callback([o, max_points] {
    o->max_map_points = static_cast<size_t>(*max_points);
    execute(*o);
  });
});

}  // namespace
}  // namespace ff::app
