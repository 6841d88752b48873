#include "flowfusion/pipeline/files_sink.h"

#include <chrono>
#include <filesystem>

#include "flowfusion/core/atomic_file.h"
#include "flowfusion/core/config.h"
#include "flowfusion/core/error.h"
#include "flowfusion/core/timings.h"
#include "flowfusion/io/tum_sequence.h"
#include "flowfusion/visualization/overlay.h"
#include "flowfusion/visualization/map_preview.h"

namespace fs = std::filesystem;

namespace ff {

FilesSink::FilesSink(FilesSinkOptions options) : options_(std::move(options)) {
  if (options_.out_dir.empty()) throw InputError("the output folder name is empty");
}

void FilesSink::begin(const RunInfo& info) {
  source_ = info.frames;
  source_name_ = info.source;
  prepareOutputDir(options_.out_dir, options_.overwrite);
  const fs::path out(options_.out_dir);
  writeJsonFile((out / "config.json").string(), nlohmann::json(info.config));
  if (options_.write_masks) fs::create_directories(out / "masks");
  if (options_.write_overlays) fs::create_directories(out / "overlays");
}

void FilesSink::frame(const RgbdFrame& frame, const FrameResult& result) {
  const fs::path out(options_.out_dir);
  const std::string stem = timestampName(frame.timestamp) + ".png";
  const auto raw = [&](const cv::Mat& m) { return source_ ? source_->toRawPixels(m) : m; };
  if (options_.write_masks) writePngAtomic((out / "masks" / stem).string(), raw(result.dynamic_mask), "mask");
  if (options_.write_overlays)
    writePngAtomic((out / "overlays" / stem).string(), raw(overlayMask(frame.color, result.dynamic_mask)), "overlay");
}

void FilesSink::exportMap(RunSummary& summary, const StaticMap& map) const {
  const fs::path out(options_.out_dir);
  if (!summary.complete) {
    summary.notes.push_back("no map written: the run did not complete");
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
  summary.export_ms = msSince(start);
  summary.written.push_back((out / "map.ply").string());
  summary.written.push_back((out / "map_points.ply").string());
  summary.written.push_back((out / "preview").string() + "/");
}

void FilesSink::end(RunSummary& summary, const FlowFusionSystem& system) {
  const fs::path out(options_.out_dir);
  writeTrajectory((out / "trajectory.txt").string(), summary.trajectory);
  summary.timings.writeCsv((out / "timings.csv").string());
  summary.written.push_back((out / "trajectory.txt").string());
  summary.written.push_back((out / "timings.csv").string());
  if (options_.write_masks) summary.written.push_back((out / "masks").string() + "/");
  if (options_.write_overlays) summary.written.push_back((out / "overlays").string() + "/");
  if (const StaticMap* map = system.map(); map && options_.export_map) exportMap(summary, *map);
  writeSummary(summary);
}

void FilesSink::writeSummary(RunSummary& summary) const {
  nlohmann::json j = toJson(summary);
  j["sequence"] = source_name_;
  const std::string path = (fs::path(options_.out_dir) / "summary.json").string();
  writeJsonFile(path, j);
  summary.written.push_back(path);
}

}  // namespace ff
