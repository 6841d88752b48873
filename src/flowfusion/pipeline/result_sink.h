#pragma once
// Where results go: the seam between the system and files, a report, a viewer, a publisher or a
// test probe (in the manner of Kimera-VIO's output callbacks). runSequence calls every sink it is
// given, in order: begin() once, frame() after each processed frame, end() once, also when the
// run stops early (then RunSummary::complete is false and says why).
#include <optional>
#include <string>
#include <vector>

#include "flowfusion/core/timings.h"
#include "flowfusion/io/frame_source.h"
#include "flowfusion/pipeline/flowfusion_system.h"

namespace ff {

struct RunInfo {
  std::string source;                   // FrameSource::name()
  const FrameSource* frames = nullptr;  // raw pixels, ground truth
  SystemConfig config;
  CameraIntrinsics camera;
  std::optional<size_t> expected_frames;  // when the source knows
};

struct RunSummary {
  bool complete = true;      // false: stopped before the source's end (interrupt or error)
  std::string stop_reason;   // why, when not complete
  Trajectory trajectory;
  size_t frames = 0;
  int tracking_failures = 0;
  int flow_restarts = 0;      // frames whose odometry restarted from the flow's rigid consensus
  double mean_rounds = 0;     // segmentation <-> odometry rounds per frame (FrameResult::iterations)
  double load_ms_median = 0;  // waiting for the next frame (reading, decoding not hidden by the read-ahead)
  double frame_ms_median = 0;  // FlowFusionSystem::process wall time per frame (its frameMs())
  double export_ms = 0;       // writing map.ply, map_points.ply and preview/ after the last frame (0: none)
  Timings timings;
  double peak_memory_mib = 0;
  size_t map_surfels = 0;
  bool map_budget_reached = false;
  std::vector<std::string> written;  // files and folders the sinks wrote
  std::vector<std::string> notes;    // what a user should know (e.g. why no mesh was written)
};

// The summary's figures as summary.json holds them (complete, stop_reason when not, frames, failures,
// restarts, rounds, map, memory, load and export times, per-stage timings, notes).
nlohmann::json toJson(const RunSummary& summary);

class ResultSink {
 public:
  virtual ~ResultSink() = default;
  virtual void begin(const RunInfo& info) {}
  virtual void frame(const RgbdFrame& frame, const FrameResult& result) {}
  // The system holds the trajectory and the map; a sink adds what it wrote to summary.written.
  virtual void end(RunSummary& summary, const FlowFusionSystem& system) {}
};

}  // namespace ff
