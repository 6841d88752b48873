#pragma once
// `run --mcap FILE`: the run as an MCAP file that Foxglove opens (io/mcap_writer.h), a ResultSink
// beside the files sink. JSON messages with the public foxglove schemas declared as JSON Schema:
//   /camera/pose         foxglove.PoseInFrame       T_world_cam per frame, frame "world"
//   /tf                  foxglove.FrameTransform    world -> camera per frame
//   /camera/path         foxglove.PosesInFrame      the whole trajectory, once at the end
//   /camera/color        foxglove.RawImage          bgr8, the frame's pixels
//   /camera/mask         foxglove.RawImage          mono8, 255 = dynamic
//   /camera/depth        foxglove.RawImage          32FC1, metres (0 = none)
//   /camera/calibration  foxglove.CameraCalibration the pinhole camera, with the first frame
//   /map                 foxglove.PointCloud        the stable surfels of the static map, at the end
// Timestamps are the frames' (the colour image's) stamps.
#include <memory>
#include <string>

#include <vector>

#include "flowfusion/pipeline/result_sink.h"

namespace ff {

class McapFileWriter;

// A point of the map as /map holds it.
struct McapMapPoint {
  Eigen::Vector3f position;  // world, metres
  uint8_t rgb[3] = {0, 0, 0};
};

class McapSink : public ResultSink {
 public:
  // Creates `path`; InputError when it cannot (or the build has no MCAP writer).
  explicit McapSink(const std::string& path);
  ~McapSink() override;
  void begin(const RunInfo& info) override;
  void frame(const RgbdFrame& frame, const FrameResult& result) override;
  // finish() with the trajectory and the map's stable surfels; adds the file to summary.written.
  void end(RunSummary& summary, const StaticMap* map) override;
  // Writes the path and the map and closes the file (convert-results calls it for a finished run).
  void finish(const Trajectory& trajectory, const std::vector<McapMapPoint>& map);

 private:
  struct Channels;
  std::unique_ptr<McapFileWriter> writer_;
  std::unique_ptr<Channels> channels_;
  CameraIntrinsics camera_;
  bool calibration_written_ = false;
};

}  // namespace ff
