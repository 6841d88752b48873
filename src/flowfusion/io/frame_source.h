#pragma once
// Where frames come from: the seam between a sensor, a recording or a program and the system.
// A source hands out RGB-D frames in time order with the pinhole camera they are in; the TUM
// folder is one implementation, a bag, a live camera or Python feed frames the same way
// (in the manner of Kimera-VIO's DataProviderInterface).
#include <chrono>
#include <memory>
#include <optional>
#include <string>

#include "flowfusion/core/camera.h"
#include "flowfusion/core/rgbd_frame.h"
#include "flowfusion/io/sequence_options.h"
#include "flowfusion/io/trajectory_io.h"

namespace ff {

// What a live source (frames arriving on their own clock, io/live_frame_queue.h) has seen so far.
struct Arrivals {
  size_t offered = 0;  // frames that arrived
  size_t dropped = 0;  // frames replaced by a newer one before the system took them
  // When the frame next() returned last arrived (steady clock): the start of its latency.
  std::chrono::steady_clock::time_point last_offered_at;
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  // The pinhole intrinsics of the frames next() returns (after any undistortion).
  virtual const CameraIntrinsics& camera() const = 0;
  // The next frame, or nullopt after the last one. Throws InputError on unreadable data.
  virtual std::optional<RgbdFrame> next() = 0;
  // Frames next() will still return when known (recordings), nullopt for live sources.
  virtual std::optional<size_t> remaining() const = 0;
  // A folder, file or device name, for summaries and messages.
  virtual std::string name() const = 0;
  // Takes a per-frame image (mask, overlay) in the pixels of next()'s frames back to the sensor's
  // raw pixels; the identity unless the source undistorts.
  virtual cv::Mat toRawPixels(const cv::Mat& image) const { return image; }
  // Ground-truth poses (camera to world, TUM convention) when the source carries them.
  virtual const Trajectory* groundtruth() const { return nullptr; }
  // Folder of ground-truth dynamic masks (<timestamp>.png) when the source carries them.
  virtual std::optional<std::string> masksDir() const { return std::nullopt; }
  // A live source's arrivals; nullopt for a source read as fast as the system asks. A live
  // source is never read ahead (runSequence): that would be the backlog it exists to avoid.
  virtual std::optional<Arrivals> arrivals() const { return std::nullopt; }
};

// A span of a recording's frames by index: "FIRST:LAST", "FIRST:" or ":LAST" (inclusive).
struct FrameRange {
  int first = 0;
  int last = -1;  // inclusive; -1 = the last frame
};
// Throws InputError quoting the text.
FrameRange parseFrameRange(const std::string& text);

// The source for `path` by what it is: a ROS 1 bag when it ends in .bag, a ROS 2 bag when it is a
// .mcap or .db3 file or a folder with metadata.yaml (io/bag_source.h), else a
// TUM-layout folder (io/tum_sequence.h, with the datasets of io/dataset_layout.h). Throws
// InputError saying what was looked for when nothing applies.
std::unique_ptr<FrameSource> openFrameSource(const std::string& path, const SequenceOptions& options,
                                             FrameRange range = {});

}  // namespace ff
