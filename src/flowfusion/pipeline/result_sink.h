#pragma once
// Where results go: the seam between the system and files, a report, a viewer, a publisher or a
// test probe (in the manner of Kimera-VIO's output callbacks). runSequence calls every sink it is
// given, in order: begin() once, frame() after each processed frame, end() once, also when the
// run stops early (then RunSummary::complete is false and says why). Each call hands over values:
// the run's setting, a frame and its result, and at the end the summary and the static map.
#include <optional>
#include <string>
#include <vector>

#include "flowfusion/core/timings.h"
#include "flowfusion/io/frame_source.h"
#include "flowfusion/pipeline/flowfusion_system.h"

namespace ff {

// A live run's figures (a source with arrivals(): `run --realtime`, a live camera or ROS node):
// what a user reads to learn whether the machine keeps up with the sensor.
struct LiveFigures {
  size_t frames_offered = 0;    // frames the source has seen arrive
  size_t frames_processed = 0;  // frames the system processed (the trajectory's poses)
  // Offered, not processed: replaced by a newer frame while the system was busy; at the end also a
  // frame still waiting, or taken and not processed, when the run stopped (offered - processed).
  size_t frames_dropped = 0;
  double latency_ms_p50 = 0;  // a frame's arrival to its FrameResult, median over processed frames
  double latency_ms_p95 = 0;  // the same, 95th percentile (linear between ranks, as numpy)
};

struct RunInfo {
  std::string source;                   // FrameSource::name()
  const FrameSource* frames = nullptr;  // raw pixels, ground truth
  SystemConfig config;
  CameraIntrinsics camera;
  std::optional<size_t> expected_frames;  // when the source knows
  // A live source's figures, updated by runSequence before every frame() call; null otherwise.
  const LiveFigures* live = nullptr;
};

struct RunSummary {
  bool complete = true;      // false: stopped before the source's end (interrupt or error)
  std::string stop_reason;   // why, when not complete
  Trajectory trajectory;          // after the last loop closure (as tracked when none closed)
  Trajectory tracked_trajectory;  // as tracked (what each FrameResult said)
  size_t frames = 0;
  int tracking_failures = 0;
  int flow_restarts = 0;      // frames whose odometry restarted from the flow's rigid consensus
  bool loop_closure = false;  // a loop-closing back end ran (slam.loop_closure and a build with Ceres)
  int loop_closures = 0;      // verified loop edges in the keyframe pose graph
  int loop_corrections = 0;   // solved graphs applied to the trajectory, the tracker and the map
  int slam_keyframes = 0;     // keyframes of the loop closer
  int lost_frames = 0;        // with loop closure: frames whose tracking failed (left out of the map)
  int relocalized_frames = 0; // of those, the ones whose pose was found again against the keyframes
  std::optional<MapReuse> map_in;  // the saved map the run continued in (`run --map-in`)
  // The loop closer's keyframes at their corrected poses, for the run's map file (slam/map_file.h).
  std::vector<SavedKeyframe> keyframes;
  double mean_rounds = 0;     // segmentation <-> odometry rounds per frame (FrameResult::iterations)
  double load_ms_median = 0;  // waiting for the next frame (reading, decoding not hidden by the read-ahead)
  double frame_ms_median = 0;  // FlowFusionSystem::process wall time per frame (its frameMs())
  double export_ms = 0;       // writing map.ply, map_points.ply and preview/ after the last frame (0: none)
  Timings timings;
  double peak_memory_mib = 0;
  size_t map_surfels = 0;
  bool map_budget_reached = false;
  std::optional<LiveFigures> live;   // a live source's figures at the end
  std::vector<std::string> written;  // files and folders the sinks wrote
  std::vector<std::string> notes;    // what a user should know (e.g. why no mesh was written)
};

// The summary's figures as summary.json holds them (complete, stop_reason when not, frames, failures,
// restarts, loop closure (loop_closure, loop_closures, loop_corrections, slam_keyframes, lost_frames, relocalized_frames),
// map_in (path, keyframes, surfels, localized_at_frame, unlocalized_frames) when the run continued in a saved map, rounds, map, memory, load and export times, per-stage timings, notes; a live run's
// frames_offered, frames_processed, frames_dropped, latency_ms_p50 and latency_ms_p95).
nlohmann::json toJson(const RunSummary& summary);

class ResultSink {
 public:
  virtual ~ResultSink() = default;
  virtual void begin(const RunInfo& info) {}
  virtual void frame(const RgbdFrame& frame, const FrameResult& result) {}
  // summary: the run's figures and trajectory; map: the static map after the last frame's fusion
  // (null when the system fused nothing). A sink adds what it wrote to summary.written.
  virtual void end(RunSummary& summary, const StaticMap* map) {}
};

}  // namespace ff
