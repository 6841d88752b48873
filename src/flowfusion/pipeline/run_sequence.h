#pragma once
// Runs the system over a sequence and writes the results: what `flowfusion run` and
// `flowfusion bench` do.
#include <functional>
#include <string>

#include "flowfusion/io/tum_sequence.h"
#include "flowfusion/pipeline/flowfusion_system.h"

namespace ff {

struct FrameRange {
  int first = 0;   // index into the associated colour frames
  int last = -1;   // inclusive; -1 = the last frame
};
// "FIRST:LAST", "FIRST:" or ":LAST" (indices, inclusive). Throws InputError.
FrameRange parseFrameRange(const std::string& text);

struct RunOptions {
  std::string out_dir;          // empty: write nothing (benchmarks)
  bool overwrite = false;       // allow a non-empty out_dir
  FrameRange frames;
  bool write_masks = true;      // out_dir/masks/<timestamp>.png
  bool write_overlays = false;  // out_dir/overlays/<timestamp>.png (mask over colour, for looking)
  bool export_map = true;       // map.ply, map_points.ply, preview/*.png
  // Called after each frame with (frames done, frames in total); e.g. a progress line.
  std::function<void(size_t, size_t)> progress;
};

struct RunSummary {
  Trajectory trajectory;
  size_t frames = 0;
  int tracking_failures = 0;
  int flow_restarts = 0;  // frames whose odometry restarted from the flow's rigid consensus
  double mean_rounds = 0;      // segmentation <-> odometry rounds per frame (FrameResult::iterations)
  double load_ms_median = 0;   // image reading and conversion, not part of the pipeline
  eval::Timings timings;
  double peak_memory_mib = 0;
  size_t map_surfels = 0;
  bool map_budget_reached = false;
  std::vector<std::string> written;  // files and folders written
};

// The sequence's ground-truth pose at its first processed frame when it has one, else identity.
SE3 initialPose(const TumSequence& sequence, size_t first_index);

// Processes frames [first, last] in order. Writes trajectory.txt, config.json, timings.csv,
// summary.json, masks/, overlays/, map.ply, map_points.ply and preview/ as asked.
RunSummary runSequence(const TumSequence& sequence, const SystemConfig& config, const RunOptions& options);

}  // namespace ff
