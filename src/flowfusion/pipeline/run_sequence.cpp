#include "flowfusion/pipeline/run_sequence.h"

#include <chrono>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "flowfusion/core/config.h"
#include "flowfusion/core/error.h"

namespace fs = std::filesystem;

namespace ff {

FrameRange parseFrameRange(const std::string& text) {
  const auto colon = text.find(':');
  const auto bad = [&]() { return InputError("--frames '" + text + "': expected FIRST:LAST (frame indices, inclusive)"); };
  if (colon == std::string::npos) throw bad();
  FrameRange r;
  const auto parse = [&](const std::string& s, int fallback) {
    if (s.empty()) return fallback;
    size_t used = 0;
    int v;
    try {
      v = std::stoi(s, &used);
    } catch (const std::exception&) {
      throw bad();
    }
    if (used != s.size() || v < 0) throw bad();
    return v;
  };
  r.first = parse(text.substr(0, colon), 0);
  r.last = parse(text.substr(colon + 1), -1);
  if (r.last >= 0 && r.last < r.first) throw bad();
  return r;
}

SE3 initialPose(const TumSequence& sequence, size_t first_index) {
  SE3 T = SE3::Identity();
  if (sequence.groundtruth() &&
      interpolatePose(*sequence.groundtruth(), sequence.entry(first_index).rgb_timestamp, T, 0.1))
    return T;
  return SE3::Identity();
}

RunSummary runSequence(const TumSequence& sequence, const SystemConfig& config, const RunOptions& options) {
  const size_t n = sequence.size();
  const size_t first = static_cast<size_t>(options.frames.first);
  const size_t last = options.frames.last < 0 ? n - 1 : static_cast<size_t>(options.frames.last);
  if (first >= n || last >= n)
    throw InputError(sequence.dir() + ": --frames " + std::to_string(options.frames.first) + ":" +
                     std::to_string(options.frames.last) + " is outside the sequence's " + std::to_string(n) +
                     " associated frames");
  const bool write = !options.out_dir.empty();
  const fs::path out(options.out_dir);
  RunSummary summary;
  if (write) {
    prepareOutputDir(options.out_dir, options.overwrite);
    writeJsonFile((out / "config.json").string(), nlohmann::json(config));
    summary.written.push_back((out / "config.json").string());
    if (options.write_masks) fs::create_directories(out / "masks");
    if (options.write_overlays) fs::create_directories(out / "overlays");
  }

  FlowFusionSystem system(config, sequence.camera(), initialPose(sequence, first));
  std::vector<double> load_ms;
  // Per-frame images are written in the input images' pixels, however the frames were loaded.
  const auto inputPixels = [&](const cv::Mat& m) {
    return sequence.undistorter() ? sequence.undistorter()->toRawPixels(m) : m;
  };
  for (size_t i = first; i <= last; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    const RgbdFrame frame = sequence.load(i);
    load_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    const FrameResult r = system.process(frame);
    if (write && options.write_masks) {
      const std::string p = (out / "masks" / (timestampName(frame.timestamp) + ".png")).string();
      if (!cv::imwrite(p, inputPixels(r.dynamic_mask))) throw InputError(p + ": cannot write mask");
    }
    if (write && options.write_overlays) {
      const std::string p = (out / "overlays" / (timestampName(frame.timestamp) + ".png")).string();
      if (!cv::imwrite(p, inputPixels(overlayMask(frame.color, r.dynamic_mask))))
        throw InputError(p + ": cannot write overlay");
    }
    ++summary.frames;
    summary.mean_rounds += r.iterations;
    if (options.progress) options.progress(i - first + 1, last - first + 1);
  }
  if (summary.frames > 0) summary.mean_rounds /= static_cast<double>(summary.frames);
  summary.trajectory = system.trajectory();
  summary.tracking_failures = system.trackingFailures();
  summary.flow_restarts = system.flowRestarts();
  summary.load_ms_median = eval::median(load_ms);
  summary.timings = system.timings();
  if (const StaticMap* map = system.map()) {
    summary.map_surfels = map->size();
    summary.map_budget_reached = map->budgetReached();
  }
  if (write) {
    writeTrajectory((out / "trajectory.txt").string(), summary.trajectory);
    summary.timings.writeCsv((out / "timings.csv").string());
    summary.written.push_back((out / "trajectory.txt").string());
    summary.written.push_back((out / "timings.csv").string());
    if (options.write_masks) summary.written.push_back((out / "masks").string() + "/");
    if (options.write_overlays) summary.written.push_back((out / "overlays").string() + "/");
    if (const StaticMap* map = system.map(); map && options.export_map) {
      map->exportMesh((out / "map.ply").string());
      map->exportPointCloud((out / "map_points.ply").string());
      writePreviews(*map, (out / "preview").string());
      summary.written.push_back((out / "map.ply").string());
      summary.written.push_back((out / "map_points.ply").string());
      summary.written.push_back((out / "preview").string() + "/");
    }
  }
  summary.peak_memory_mib = eval::peakResidentMiB();
  if (write) {
    nlohmann::json j;
    j["sequence"] = sequence.dir();
    j["frames"] = summary.frames;
    j["tracking_failures"] = summary.tracking_failures;
    j["flow_restarts"] = summary.flow_restarts;
    j["mean_rounds"] = summary.mean_rounds;
    j["map_surfels"] = summary.map_surfels;
    j["map_budget_reached"] = summary.map_budget_reached;
    j["peak_memory_mib"] = summary.peak_memory_mib;
    j["timings"] = summary.timings.toJson()["stages"];
    writeJsonFile((out / "summary.json").string(), j);
    summary.written.push_back((out / "summary.json").string());
  }
  return summary;
}

}  // namespace ff
