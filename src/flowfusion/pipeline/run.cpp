#include "flowfusion/pipeline/run.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>

#include "flowfusion/core/timings.h"
#include "flowfusion/core/process_memory.h"
#include "flowfusion/io/prefetching_source.h"

namespace ff {

SE3 initialPose(const FrameSource& source, double timestamp) {
  SE3 T = SE3::Identity();
  if (const Trajectory* gt = source.groundtruth(); gt && interpolatePose(*gt, timestamp, T, 0.1)) return T;
  return SE3::Identity();
}

nlohmann::json toJson(const RunSummary& summary) {
  nlohmann::json j;
  j["complete"] = summary.complete;
  if (!summary.complete) j["stop_reason"] = summary.stop_reason;
  j["frames"] = summary.frames;
  j["tracking_failures"] = summary.tracking_failures;
  j["flow_restarts"] = summary.flow_restarts;
  j["loop_closure"] = summary.loop_closure;
  j["loop_closures"] = summary.loop_closures;
  j["loop_corrections"] = summary.loop_corrections;
  j["slam_keyframes"] = summary.slam_keyframes;
  j["lost_frames"] = summary.lost_frames;
  j["relocalized_frames"] = summary.relocalized_frames;
  if (const std::optional<MapReuse>& m = summary.map_in)
    j["map_in"] = {{"path", m->path},
                   {"keyframes", m->keyframes},
                   {"surfels", m->surfels},
                   {"localized_at_frame", m->localized_at_frame},
                   {"unlocalized_frames", m->unlocalized_frames}};
  j["mean_rounds"] = summary.mean_rounds;
  j["map_surfels"] = summary.map_surfels;
  j["map_budget_reached"] = summary.map_budget_reached;
  j["peak_memory_mib"] = summary.peak_memory_mib;
  j["load_ms_median"] = summary.load_ms_median;
  j["frame_ms_median"] = summary.frame_ms_median;
  j["export_ms"] = summary.export_ms;
  j["timings"] = summary.timings.toJson()["stages"];
  if (summary.live) {
    j["frames_offered"] = summary.live->frames_offered;
    j["frames_processed"] = summary.live->frames_processed;
    j["frames_dropped"] = summary.live->frames_dropped;
    j["latency_ms_p50"] = summary.live->latency_ms_p50;
    j["latency_ms_p95"] = summary.live->latency_ms_p95;
  }
  j["notes"] = summary.notes;
  return j;
}

void summariseSystem(RunSummary& s, const FlowFusionSystem& system, long summed_rounds) {
  if (s.frames > 0) s.mean_rounds = static_cast<double>(summed_rounds) / static_cast<double>(s.frames);
  s.tracked_trajectory = system.trajectory();
  s.trajectory = system.closedTrajectory();
  s.loop_closure = system.loopClosureActive();
  s.loop_closures = system.loopClosures();
  s.loop_corrections = system.loopCorrections();
  s.slam_keyframes = system.slamKeyframes();
  s.lost_frames = system.lostFrames();
  s.relocalized_frames = system.relocalizedFrames();
  if (!system.loopClosureNote().empty()) s.notes.push_back(system.loopClosureNote());
  s.map_in = system.mapReuse();
  if (s.map_in && s.map_in->localized_at_frame < 0)
    s.notes.push_back("never localized in the saved map " + s.map_in->path + ": none of the " +
                      std::to_string(s.map_in->unlocalized_frames) +
                      " frames matched its keyframes, so the trajectory holds no poses and nothing was fused");
  s.keyframes = system.savedKeyframes();
  s.tracking_failures = system.trackingFailures();
  s.flow_restarts = system.flowRestarts();
  if (!system.frameMs().empty()) s.frame_ms_median = median(system.frameMs());
  s.timings = system.timings();
  if (const StaticMap* map = system.map()) {
    s.map_surfels = map->size();
    s.map_budget_reached = map->budgetReached();
  }
  s.peak_memory_mib = peakResidentMiB();
}

namespace {

// Reads the next frame and records how long the run waited for it (with read-ahead: the decoding
// the previous frame's processing did not hide).
std::optional<RgbdFrame> nextFrame(FrameSource& source, std::vector<double>& load_ms) {
  const auto t0 = std::chrono::steady_clock::now();
  std::optional<RgbdFrame> frame = source.next();
  load_ms.push_back(msSince(t0));
  return frame;
}

// The q-quantile (q in [0, 1]) of sorted values, linear between ranks as numpy's default; 0 when empty.
double quantileOfSorted(const std::vector<double>& sorted, double q) {
  if (sorted.empty()) return 0;
  const double rank = q * static_cast<double>(sorted.size() - 1);
  const size_t below = static_cast<size_t>(std::floor(rank));
  const size_t above = std::min(below + 1, sorted.size() - 1);
  return sorted[below] + (rank - static_cast<double>(below)) * (sorted[above] - sorted[below]);
}

// A live source's figures as the run goes: each processed frame's latency from its arrival (kept
// sorted, so the percentiles are at hand for the sinks after every frame) and the source's counts.
class LiveMeter {
 public:
  explicit LiveMeter(const FrameSource& source) : source_(source) {}

  // Right after the frame next() returned last was processed.
  void processed() {
    const Arrivals a = *source_.arrivals();
    const double latency_ms = msSince(a.last_offered_at);
    sorted_latency_ms_.insert(std::upper_bound(sorted_latency_ms_.begin(), sorted_latency_ms_.end(), latency_ms),
                              latency_ms);
    update(a, a.dropped);
  }
  // At the end: every frame offered and not processed counts as dropped.
  void finish() {
    const Arrivals a = *source_.arrivals();
    update(a, a.offered - std::min(a.offered, sorted_latency_ms_.size()));
  }
  const LiveFigures& figures() const { return figures_; }

 private:
  void update(const Arrivals& a, size_t dropped) {
    figures_.frames_offered = a.offered;
    figures_.frames_processed = sorted_latency_ms_.size();
    figures_.frames_dropped = dropped;
    figures_.latency_ms_p50 = quantileOfSorted(sorted_latency_ms_, 0.5);
    figures_.latency_ms_p95 = quantileOfSorted(sorted_latency_ms_, 0.95);
  }

  const FrameSource& source_;
  std::vector<double> sorted_latency_ms_;
  LiveFigures figures_;
};

// The summary of runSequence's loop: the system's figures, the read time and a live run's figures.
void summarise(RunSummary& s, FlowFusionSystem& system, long summed_rounds, const std::vector<double>& load_ms,
               std::optional<LiveMeter>& live) {
  if (live) {
    live->finish();
    s.live = live->figures();
  }
  system.finishLoopClosure();
  summariseSystem(s, system, summed_rounds);
  s.load_ms_median = median(load_ms);
}

void endSinks(const std::vector<ResultSink*>& sinks, RunSummary& s, const FlowFusionSystem& system) {
  const StaticMap* map = system.map();
  for (ResultSink* sink : sinks) sink->end(s, map);
}

}  // namespace

RunSummary runSequence(FrameSource& source, const SystemConfig& config, const std::vector<ResultSink*>& sinks,
                       const RunControl& control) {
  validate(config);
  std::optional<LiveMeter> live;
  if (source.arrivals()) live.emplace(source);
  const RunInfo info{source.name(), &source, config, source.camera(), source.remaining(),
                     live ? &live->figures() : nullptr};
  for (ResultSink* sink : sinks) sink->begin(info);
  std::optional<PrefetchingSource> prefetching;  // never for a live source: a backlog of frames
  if (control.prefetch_frames > 0 && !live) prefetching.emplace(source, control.prefetch_frames);
  FrameSource& frames = prefetching ? static_cast<FrameSource&>(*prefetching) : source;
  std::vector<double> load_ms;
  std::unique_ptr<FlowFusionSystem> system;
  RunSummary summary;
  long summed_rounds = 0;  // FrameResult::iterations over the frames
  try {
    for (std::optional<RgbdFrame> frame = nextFrame(frames, load_ms); frame; frame = nextFrame(frames, load_ms)) {
      if (control.stop && control.stop->load()) {
        summary.complete = false;
        summary.stop_reason = control.reason && *control.reason ? *control.reason : "stopped";
        break;
      }
      // The first frame's time gives the start pose from the ground truth.
      if (!system)
        system = std::make_unique<FlowFusionSystem>(config, source.camera(), initialPose(source, frame->timestamp),
                                                    control.map_in);
      const FrameResult r = system->process(*frame);
      if (live) live->processed();
      for (ResultSink* sink : sinks) sink->frame(*frame, r);
      ++summary.frames;
      summed_rounds += r.iterations;
      if (control.after_frame) control.after_frame(*system);
    }
  } catch (const std::exception& e) {
    summary.complete = false;
    summary.stop_reason = e.what();
    if (!system) system = std::make_unique<FlowFusionSystem>(config, source.camera());
    summarise(summary, *system, summed_rounds, load_ms, live);
    try {
      endSinks(sinks, summary, *system);
    } catch (const std::exception&) {
      // The frame's own error is the one to report.
    }
    throw;
  }
  if (!system) system = std::make_unique<FlowFusionSystem>(config, source.camera());
  summarise(summary, *system, summed_rounds, load_ms, live);
  endSinks(sinks, summary, *system);
  return summary;
}

}  // namespace ff
