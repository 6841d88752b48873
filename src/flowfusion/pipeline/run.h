#pragma once
// A run: frames from a source, through the system, to the sinks (`flowfusion run`, `bench`, the
// Python package). The loop knows nothing of files; FilesSink (sinks/files_sink.h) writes them.
#include <atomic>
#include <functional>
#include <vector>

#include "flowfusion/io/frame_source.h"
#include "flowfusion/pipeline/result_sink.h"

namespace ff {

struct RunControl {
  // Checked before each frame: when set, the run stops there and ends its sinks with
  // RunSummary::complete = false and stop_reason = *reason (e.g. a signal handler's flag).
  const std::atomic<bool>* stop = nullptr;
  const char* const* reason = nullptr;
  // Frames read ahead on a worker thread while the current one is processed (io/prefetching_source.h);
  // 0 reads each frame on the run's thread when it is needed (for a source whose next() must stay there).
  size_t prefetch_frames = 2;
  // Called on the run's thread after each frame's sinks with the system as it stands then (map and
  // trajectory up to that frame): a live node publishes its map now and then and saves on request
  // (ros/). The system lives until runSequence returns.
  std::function<void(const FlowFusionSystem&)> after_frame = {};
  // A previous run's map to continue in (`run --map-in`; FlowFusionSystem's map_in): the run's
  // poses are found in its world frame instead of starting at the ground truth's first pose.
  const SavedMap* map_in = nullptr;
};

// The ground truth's pose at `timestamp` (s) when the source has one, else identity.
SE3 initialPose(const FrameSource& source, double timestamp);

// What a run's summary takes from the system after its last frame, for runSequence and for any
// loop of its own (the Python System's save()): trajectory, tracking failures, flow restarts,
// per-stage timings, process()'s median wall time, the map's size, the peak memory, and
// mean_rounds from summed_rounds (FrameResult::iterations summed over summary.frames frames).
void summariseSystem(RunSummary& summary, const FlowFusionSystem& system, long summed_rounds);

// Processes every frame of `source`. A frame that throws (also one the read-ahead failed to read)
// ends the sinks with an incomplete summary (the frames before it kept) and is rethrown.
// A live source (FrameSource::arrivals(): io/live_frame_queue.h, io/realtime_replay.h) is not read
// ahead; the run measures each frame's latency from its arrival to its FrameResult and keeps the
// LiveFigures for the sinks (RunInfo::live, updated before each frame()) and the summary.
RunSummary runSequence(FrameSource& source, const SystemConfig& config, const std::vector<ResultSink*>& sinks,
                       const RunControl& control = {});

}  // namespace ff
