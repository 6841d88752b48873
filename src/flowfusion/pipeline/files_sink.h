#pragma once
// The result sink that writes a run's files into one output folder (what `flowfusion run`
// leaves): config.json at the start, masks/ and overlays/ per frame, then trajectory.txt,
// timings.csv, the map (map.ply, map_points.ply, preview/) and summary.json. Every file is
// written atomically; summary.json says whether the run is complete and, if not, why.
#include <string>

#include "flowfusion/pipeline/result_sink.h"

namespace ff {

struct FilesSinkOptions {
  std::string out_dir;
  bool overwrite = false;       // allow a non-empty out_dir
  bool write_masks = true;      // masks/<timestamp>.png, 255 = dynamic, in the source's raw pixels
  bool write_overlays = false;  // overlays/<timestamp>.png: mask over colour, for looking
  bool export_map = true;       // map.ply, map_points.ply, preview/*.png
};

class FilesSink : public ResultSink {
 public:
  explicit FilesSink(FilesSinkOptions options);
  void begin(const RunInfo& info) override;
  void frame(const RgbdFrame& frame, const FrameResult& result) override;
  void end(RunSummary& summary, const FlowFusionSystem& system) override;

  const std::string& outDir() const { return options_.out_dir; }

 private:
  void exportMap(RunSummary& summary, const StaticMap& map) const;
  void writeSummary(RunSummary& summary) const;

  FilesSinkOptions options_;
  const FrameSource* source_ = nullptr;
  std::string source_name_;
};

}  // namespace ff
