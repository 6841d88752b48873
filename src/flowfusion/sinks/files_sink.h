#pragma once
// The result sink that writes a run's files into one output folder (what `flowfusion run`
// leaves): config.json at the start, masks/, overlays/ and clusters/ per frame, then trajectory.txt,
// timings.csv, the map (map.ply, map_points.ply, preview/, and map.ffmap for a next run's --map-in:
// slam/map_file.h) and summary.json. Every file is
// written atomically; summary.json says whether the run is complete and, if not, why.
//
// The masks and overlays are encoded and written on one writer thread, so the PNG encoding does
// not hold up the run (as the read-ahead hides the decoding). At most a few frames wait for it
// (frame() blocks while they do, so memory stays bounded); a failed write is thrown by the next
// frame() or by end(), which first writes every image still waiting and then the rest of the run's
// files, with summary.json saying the run is incomplete and why. The source's toRawPixels() is
// called on that thread (const members of every source in io/ allow that).
#include <exception>
#include <memory>
#include <string>

#include "flowfusion/pipeline/result_sink.h"

namespace ff {

struct FilesSinkOptions {
  std::string out_dir;
  bool overwrite = false;       // allow a non-empty out_dir
  bool write_masks = true;      // masks/<timestamp>.png, 255 = dynamic, in the source's raw pixels
  bool write_overlays = false;  // overlays/<timestamp>.png: mask over colour, for looking
  // clusters/<timestamp>.csv and .png: each cluster's evidence and score (FrameResult::clusters,
  // pipeline.cluster_log) and the clusters' labels in the source's raw pixels (docs/formats.md)
  bool write_clusters = false;
  bool export_map = true;       // map.ply, map_points.ply, preview/*.png, map.ffmap
};

class FilesSink : public ResultSink {
 public:
  explicit FilesSink(FilesSinkOptions options);
  // Without end(): stops the writer thread after the image it is writing (the others are dropped).
  ~FilesSink() override;
  FilesSink(const FilesSink&) = delete;
  FilesSink& operator=(const FilesSink&) = delete;

  void begin(const RunInfo& info) override;
  void frame(const RgbdFrame& frame, const FrameResult& result) override;
  void end(RunSummary& summary, const StaticMap* map) override;
  // masks/<timestamp>.png as frame() writes it, for a result kept without its frame (the Python
  // System's save()); `dynamic_mask` in the system's pixels, taken back by the source's toRawPixels.
  void writeMask(double timestamp, const cv::Mat& dynamic_mask);
  // clusters/<timestamp>.csv and .png when write_clusters and the result carries a cluster log;
  // `image_size`: the system's input size, which the labels are brought to.
  void writeClusters(double timestamp, const ClusterLog& log, const cv::Size& image_size);

 private:
  class ImageWriter;

  std::exception_ptr finishImages(RunSummary& summary);
  void exportMap(RunSummary& summary, const StaticMap& map) const;
  void writeSummary(RunSummary& summary) const;

  FilesSinkOptions options_;
  const FrameSource* source_ = nullptr;
  CameraIntrinsics camera_;  // for the map file
  SlamConfig slam_;
  std::string source_name_;
  std::unique_ptr<ImageWriter> writer_;
};

}  // namespace ff
