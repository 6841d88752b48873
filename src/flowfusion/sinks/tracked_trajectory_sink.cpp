#include "flowfusion/sinks/tracked_trajectory_sink.h"

#include <filesystem>

namespace ff {

void TrackedTrajectorySink::end(RunSummary& summary, const StaticMap*) {
  if (!summary.loop_closure) return;
  const std::string path = (std::filesystem::path(out_dir_) / "trajectory_tracked.txt").string();
  writeTrajectory(path, summary.tracked_trajectory);
  summary.written.push_back(path);
}

}  // namespace ff
