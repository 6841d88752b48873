#pragma once
// One run of the system over the frames the node offers, from the first frame after the node
// started (or was reset) to the next reset or shutdown: a live source (a queue of one,
// io/live_frame_queue.h), runSequence on its own thread with the publishing sink, and, when
// ~save_dir is set, the run's masks kept (PNG, in memory) so that ~save can write the files `run`
// writes at any time. The system is read between frames only: while a frame is processed the run
// holds the source, and ~save waits for it.
#include <atomic>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "flowfusion/io/live_frame_queue.h"
#include "flowfusion/ros/publisher_sink.h"

namespace ff::rosnode {

class LiveSession {
 public:
  // `intake` knows the camera. The references outlive the session.
  LiveSession(const NodeParams& params, const FrameIntake& intake, const Publishers& publishers);
  // stop() unless it was called.
  ~LiveSession();
  LiveSession(const LiveSession&) = delete;
  LiveSession& operator=(const LiveSession&) = delete;

  // From the subscriber's thread: replaces (drops) a frame still waiting.
  void offer(RgbdFrame frame);
  // The files `run` writes for the frames processed so far, into ~save_dir (the summary says it is
  // a snapshot of a live run); returns what was written. InputError without ~save_dir, before the
  // first frame, or when a file cannot be written.
  std::string save();
  // Ends the run after the frame it is processing and the one waiting; with `save_partial` (and
  // ~save_dir set) the run so far is written, marked partial with `reason` (summary.json).
  void stop(const std::string& reason, bool save_partial);
  LiveFigures figures() const { return publisher_.figures(); }
  // The run ended on its own (an error it logged): frames offered now go nowhere.
  bool ended() const { return ended_; }

 private:
  class Source;
  class KeptRun;
  void run();

  const NodeParams& params_;
  std::unique_ptr<Source> source_;
  PublisherSink publisher_;
  std::unique_ptr<KeptRun> kept_;  // null without ~save_dir
  const FlowFusionSystem* system_ = nullptr;  // between the first frame and the run's end, under the source's lock
  bool stopped_ = false;
  std::atomic<bool> ended_{false};
  std::thread thread_;  // last
};

}  // namespace ff::rosnode
