#pragma once
// Writes trajectory_tracked.txt (TUM format) beside the files sink's trajectory.txt when loop
// closure ran: trajectory.txt holds the poses after the last loop closure, this file the poses as
// they were tracked (each frame's FrameResult, before any correction). Attach it after the
// FilesSink, which prepares the folder.
#include <string>

#include "flowfusion/pipeline/result_sink.h"

namespace ff {

class TrackedTrajectorySink : public ResultSink {
 public:
  explicit TrackedTrajectorySink(std::string out_dir) : out_dir_(std::move(out_dir)) {}
  void end(RunSummary& summary, const StaticMap* map) override;

 private:
  std::string out_dir_;
};

}  // namespace ff
