#include "flowfusion/ros/live_session.h"

#include <atomic>
#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <ros/console.h>
#include <stdexcept>

#include "flowfusion/core/error.h"
#include "flowfusion/core/output_folder.h"
#include "flowfusion/sinks/files_sink.h"
#include "flowfusion/pipeline/run.h"

namespace ff::rosnode {

namespace {

// How stop() ends the run: the live source fails with it after its last frame.
struct StopRequest : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace

// The live queue in the camera's pinhole pixels, with the way back to the colour image's, held by
// the run's thread from the moment next() returns a frame until it asks for the next one.
class LiveSession::Source : public FrameSource {
 public:
  Source(const CameraIntrinsics& camera, std::shared_ptr<const Undistorter> undistorter)
      : queue_(camera, "ros"), undistorter_(std::move(undistorter)) {}

  const CameraIntrinsics& camera() const override { return queue_.camera(); }
  std::optional<RgbdFrame> next() override {
    if (held_.owns_lock()) held_.unlock();
    struct Relock {
      std::unique_lock<std::mutex>& lock;
      ~Relock() { lock.lock(); }
    } relock{held_};
    return queue_.next();
  }
  std::optional<size_t> remaining() const override { return std::nullopt; }
  std::string name() const override { return queue_.name(); }
  cv::Mat toRawPixels(const cv::Mat& image) const override {
    return undistorter_ ? undistorter_->toRawPixels(image) : image;
  }
  std::optional<Arrivals> arrivals() const override { return queue_.arrivals(); }

  LiveFrameQueue& queue() { return queue_; }
  // The run's thread, after runSequence returned.
  void release() {
    if (held_.owns_lock()) held_.unlock();
  }
  // Another thread: waits while a frame is processed.
  std::mutex& idle() { return mutex_; }

 private:
  LiveFrameQueue queue_;
  std::shared_ptr<const Undistorter> undistorter_;
  std::mutex mutex_;
  std::unique_lock<std::mutex> held_{mutex_, std::defer_lock};
};

// The masks of the run (PNG in memory, in the colour image's pixels) and what the files need besides
// the system: the FilesSink of `run`, driven with them, writes the same files at any time.
class LiveSession::KeptRun : public ResultSink {
 public:
  explicit KeptRun(std::string dir) : dir_(std::move(dir)) {}

  void begin(const RunInfo& info) override {
    info_ = info;
    info_.frames = nullptr;  // the masks are kept in raw pixels already
    info_.live = nullptr;
    source_ = info.frames;
  }
  void frame(const RgbdFrame& frame, const FrameResult& result) override {
    std::vector<uint8_t> png;
    cv::imencode(".png", source_->toRawPixels(result.dynamic_mask), png, {cv::IMWRITE_PNG_COMPRESSION, 1});
    masks_.push_back({frame.timestamp, std::move(png)});
    rounds_ += result.iterations;
  }
  void end(RunSummary& summary, const StaticMap* map) override {
    if (!save_at_end_) return;
    // On stderr: ROS's logging has shut down with the node.
    try {
      RunSummary partial = summary;
      std::fprintf(stderr, "flowfusion: %s\n", write(partial, map).c_str());
    } catch (const std::exception& e) {
      std::fprintf(stderr, "flowfusion: error: writing the partial result failed: %s\n", e.what());
    }
  }

  // The summary of the run so far as runSequence would give it.
  RunSummary summarySoFar(const FlowFusionSystem& system) const {
    RunSummary s;
    s.frames = masks_.size();
    summariseSystem(s, system, rounds_);
    return s;
  }
  std::string write(RunSummary& summary, const StaticMap* map) {
    FilesSinkOptions options;
    options.out_dir = dir_;
    options.overwrite = true;  // the node's own earlier saves (the folder's manifest)
    FilesSink files(options);
    struct Release {
      ~Release() { releaseOutputDir(); }
    } release;
    files.begin(info_);
    for (const auto& [timestamp, png] : masks_) files.writeMask(timestamp, cv::imdecode(png, cv::IMREAD_GRAYSCALE));
    files.end(summary, map);
    return "wrote " + std::to_string(summary.frames) + " frames into " + dir_ +
           (summary.complete ? "" : " (partial: " + summary.stop_reason + ")");
  }
  void saveAtEnd(bool save) { save_at_end_ = save; }

 private:
  std::string dir_;
  RunInfo info_;
  const FrameSource* source_ = nullptr;
  std::vector<std::pair<double, std::vector<uint8_t>>> masks_;
  long rounds_ = 0;
  std::atomic<bool> save_at_end_{false};  // set by stop(), read on the run's thread
};

LiveSession::LiveSession(const NodeParams& params, const FrameIntake& intake, const Publishers& publishers)
    : params_(params),
      source_(std::make_unique<Source>(intake.camera()->intrinsics, intake.undistorter())),
      publisher_(publishers, params, intake) {
  if (!params.save_dir.empty()) kept_ = std::make_unique<KeptRun>(params.save_dir);
  thread_ = std::thread([this] { run(); });
}

LiveSession::~LiveSession() {
  if (!stopped_) stop("node shut down", false);
}

void LiveSession::offer(RgbdFrame frame) { source_->queue().offer(std::move(frame)); }

void LiveSession::run() {
  RunControl control;
  control.prefetch_frames = 0;
  control.after_frame = [this](const FlowFusionSystem& system) {
    system_ = &system;
    publisher_.publishMapWhenDue(system);
  };
  std::vector<ResultSink*> sinks = {&publisher_};
  if (kept_) sinks.push_back(kept_.get());
  try {
    runSequence(*source_, params_.config, sinks, control);
  } catch (const StopRequest&) {
  } catch (const std::exception& e) {
    ROS_ERROR_STREAM("flowfusion: the run stopped: " << e.what() << " (the next frame starts a new one)");
  }
  system_ = nullptr;  // still under the source's lock: the system is gone
  source_->release();
  ended_ = true;
}

std::string LiveSession::save() {
  if (!kept_) throw InputError("no ~save_dir parameter: set it to the folder ~save writes into");
  std::lock_guard idle(source_->idle());
  if (!system_) throw InputError("no frame processed yet");
  RunSummary summary = kept_->summarySoFar(*system_);
  summary.live = publisher_.figures();
  summary.notes.push_back("a snapshot of a live run (flowfusion ros, ~save) after " + std::to_string(summary.frames) +
                          " frames; the node went on");
  return kept_->write(summary, system_->map());
}

void LiveSession::stop(const std::string& reason, bool save_partial) {
  stopped_ = true;
  if (kept_) kept_->saveAtEnd(save_partial);
  source_->queue().fail(std::make_exception_ptr(StopRequest(reason)));
  if (thread_.joinable()) thread_.join();
}

}  // namespace ff::rosnode
