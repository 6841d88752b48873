#include "flowfusion/sinks/files_sink.h"

#include <chrono>
#include <condition_variable>
#include <deque>
#include <exception>
#include <filesystem>
#include <functional>
#include <mutex>
#include <stdexcept>
#include <thread>

#include <opencv2/imgproc.hpp>

#include "flowfusion/core/atomic_file.h"
#include "flowfusion/core/config.h"
#include "flowfusion/core/error.h"
#include "flowfusion/core/timings.h"
#include "flowfusion/io/tum_sequence.h"
#include "flowfusion/slam/map_file.h"
#include "flowfusion/visualization/overlay.h"
#include "flowfusion/visualization/map_preview.h"

namespace fs = std::filesystem;

namespace ff {

namespace {
constexpr size_t kWaitingImages = 4;  // images queued for the writer at most (2 to 4 frames)

// An image of the system's pixels in the source's raw pixels (the same without a source).
cv::Mat inRawPixels(const FrameSource* source, const cv::Mat& image) {
  return source ? source->toRawPixels(image) : image;
}
}  // namespace

// Runs write jobs on one thread in the order given, at most `depth` waiting. After a job fails the
// ones after it are dropped, and every later push() and finish() rethrows the failure.
class FilesSink::ImageWriter {
 public:
  explicit ImageWriter(size_t depth) : depth_(depth), worker_([this] { work(); }) {}
  ~ImageWriter() { stop(); }

  // Waits while `depth` jobs are waiting.
  void push(std::function<void()> job) {
    std::unique_lock lock(mutex_);
    changed_.wait(lock, [this] { return error_ || stopping_ || jobs_.size() < depth_; });
    if (error_) std::rethrow_exception(error_);
    if (stopping_) throw std::logic_error("FilesSink: frame() after end()");
    jobs_.push_back(std::move(job));
    changed_.notify_all();
  }

  // Waits until every job ran or one failed, and stops the thread.
  void finish() {
    {
      std::unique_lock lock(mutex_);
      changed_.wait(lock, [this] { return error_ || (jobs_.empty() && !busy_); });
    }
    stop();
    if (error_) std::rethrow_exception(error_);
  }

 private:
  void stop() {
    {
      std::lock_guard lock(mutex_);
      stopping_ = true;
    }
    changed_.notify_all();
    if (worker_.joinable()) worker_.join();
  }

  void work() {
    for (;;) {
      std::function<void()> job;
      {
        std::unique_lock lock(mutex_);
        changed_.wait(lock, [this] { return stopping_ || !jobs_.empty(); });
        if (stopping_) return;
        job = std::move(jobs_.front());
        jobs_.pop_front();
        busy_ = true;
      }
      changed_.notify_all();
      std::exception_ptr error;
      try {
        job();
      } catch (...) {
        error = std::current_exception();
      }
      {
        std::lock_guard lock(mutex_);
        busy_ = false;
        if (error) {
          error_ = error;
          jobs_.clear();
        }
      }
      changed_.notify_all();
      if (error) return;
    }
  }

  const size_t depth_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<std::function<void()>> jobs_;
  std::exception_ptr error_;  // the first failed job's
  bool busy_ = false;         // a job is running
  bool stopping_ = false;
  std::thread worker_;  // last: starts once the members above exist
};

FilesSink::FilesSink(FilesSinkOptions options) : options_(std::move(options)) {
  if (options_.out_dir.empty()) throw InputError("the output folder name is empty");
}

FilesSink::~FilesSink() = default;

void FilesSink::begin(const RunInfo& info) {
  source_ = info.frames;
  camera_ = info.camera;
  slam_ = info.config.slam;
  // Absolute, so that `report` finds the sequence from any folder.
  std::error_code ec;
  source_name_ = info.frames && fs::exists(info.source, ec) ? fs::absolute(info.source).lexically_normal().string()
                                                             : info.source;
  prepareOutputDir(options_.out_dir, options_.overwrite);
  const fs::path out(options_.out_dir);
  writeJsonFile((out / "config.json").string(), nlohmann::json(info.config));
  if (options_.write_masks) fs::create_directories(out / "masks");
  if (options_.write_overlays) fs::create_directories(out / "overlays");
  if (options_.write_clusters) fs::create_directories(out / "clusters");
  if (options_.write_masks || options_.write_overlays || options_.write_clusters)
    writer_ = std::make_unique<ImageWriter>(kWaitingImages);
}

void FilesSink::frame(const RgbdFrame& frame, const FrameResult& result) {
  writeMask(frame.timestamp, result.dynamic_mask);
  writeClusters(frame.timestamp, result.clusters, result.dynamic_mask.size());
  // Copies: the caller may change its images once frame() returns.
  if (writer_ && options_.write_overlays)
    writer_->push([path = (fs::path(options_.out_dir) / "overlays" / (timestampName(frame.timestamp) + ".png")).string(),
                   color = frame.color.clone(), mask = result.dynamic_mask.clone(), source = source_] {
      writePngAtomic(path, inRawPixels(source, overlayMask(color, mask)), "overlay");
    });
}

void FilesSink::writeMask(double timestamp, const cv::Mat& dynamic_mask) {
  if (!writer_ || !options_.write_masks) return;
  writer_->push([path = (fs::path(options_.out_dir) / "masks" / (timestampName(timestamp) + ".png")).string(),
                 mask = dynamic_mask.clone(), source = source_] {
    writePngAtomic(path, inRawPixels(source, mask), "mask");
  });
}

void FilesSink::writeClusters(double timestamp, const ClusterLog& log, const cv::Size& image_size) {
  if (!writer_ || !options_.write_clusters || log.empty()) return;
  // Labels + 1 (0: no cluster) in 16 bits, at the input's size.
  cv::Mat labels16, full;
  log.labels.convertTo(labels16, CV_16U, 1.0, 1.0);
  cv::resize(labels16, full, image_size, 0, 0, cv::INTER_NEAREST);
  const fs::path base = fs::path(options_.out_dir) / "clusters" / timestampName(timestamp);
  writer_->push([csv_path = base.string() + ".csv", png_path = base.string() + ".png", csv = clusterLogCsv(log),
                 labels = std::move(full), source = source_] {
    writeFileAtomic(csv_path, csv, "cluster log");
    writePngAtomic(png_path, inRawPixels(source, labels), "cluster labels");
  });
}

// Waits for the images still queued. A failed write makes the run incomplete (or, when it already
// is, adds a note); its error is returned for end() to rethrow once the other files are written.
std::exception_ptr FilesSink::finishImages(RunSummary& summary) {
  if (!writer_) return nullptr;
  try {
    writer_->finish();
  } catch (const std::exception& e) {
    if (summary.complete) {
      summary.complete = false;
      summary.stop_reason = e.what();
    } else if (summary.stop_reason != e.what()) {
      summary.notes.push_back(std::string("writing an image failed: ") + e.what());
    }
    return std::current_exception();
  }
  return nullptr;
}

void FilesSink::exportMap(RunSummary& summary, const StaticMap& map) const {
  const fs::path out(options_.out_dir);
  if (!summary.complete) {
    summary.notes.push_back("no map written: the run did not complete");
    return;
  }
  if (summary.map_in && summary.map_in->localized_at_frame < 0) {
    summary.notes.push_back("no map written: the run never localized in the saved map (it holds only that map)");
    return;
  }
  if (!map.hasStableSurfels()) {
    summary.notes.push_back("no map written: the map holds no stable surfels (too few frames or no valid depth)");
    return;
  }
  const auto start = std::chrono::steady_clock::now();
  map.exportMesh((out / "map.ply").string());
  map.exportPointCloud((out / "map_points.ply").string());
  writePreviews(map, (out / "preview").string());
  summary.written.push_back((out / "map.ply").string());
  summary.written.push_back((out / "map_points.ply").string());
  summary.written.push_back((out / "preview").string() + "/");
  if (summary.keyframes.empty()) {
    summary.notes.push_back(std::string("no ") + kMapFileName + " written: no keyframes (loop closure off)");
  } else {
    writeMapFile((out / kMapFileName).string(), savedMap(&map, summary.keyframes, camera_, slam_));
    summary.written.push_back((out / kMapFileName).string());
  }
  summary.export_ms = msSince(start);
}

void FilesSink::end(RunSummary& summary, const StaticMap* map) {
  const std::exception_ptr image_error = finishImages(summary);
  const fs::path out(options_.out_dir);
  writeTrajectory((out / "trajectory.txt").string(), summary.trajectory);
  summary.timings.writeCsv((out / "timings.csv").string());
  summary.written.push_back((out / "trajectory.txt").string());
  summary.written.push_back((out / "timings.csv").string());
  if (options_.write_masks) summary.written.push_back((out / "masks").string() + "/");
  if (options_.write_overlays) summary.written.push_back((out / "overlays").string() + "/");
  if (options_.write_clusters) summary.written.push_back((out / "clusters").string() + "/");
  if (map && options_.export_map) exportMap(summary, *map);
  writeSummary(summary);
  if (image_error) std::rethrow_exception(image_error);
}

void FilesSink::writeSummary(RunSummary& summary) const {
  nlohmann::json j = toJson(summary);
  j["sequence"] = source_name_;
  const std::string path = (fs::path(options_.out_dir) / "summary.json").string();
  writeJsonFile(path, j);
  summary.written.push_back(path);
}

}  // namespace ff
