#pragma once
// ROS bags as RGB-D recordings: ROS 1 bags (format 2.0, uncompressed, bz2 or lz4 chunks) and ROS 2
// bags (a rosbag2 folder, or one .mcap or .db3 file; io/ros_recording.h says which code reads the
// container and messages of each). A colour topic
// (sensor_msgs/Image rgb8, bgr8, mono8, rgba8, bgra8, or sensor_msgs/CompressedImage png/jpeg),
// a depth topic (sensor_msgs/Image 16UC1 or mono16 in raw units, 32FC1 in metres) and the camera
// from sensor_msgs/CameraInfo. Colour and depth are associated by their header stamps as the
// TUM folders are (io/tum_text.h associate()). Reading streams: open() reads each image message
// once for its stamp and encoding and keeps only those; read() decodes one pair, so memory does
// not grow with the bag's length. ROS 1 bags need Debian's librosbag-storage-dev, ROS 2 bags
// libzstd-dev, liblz4-dev and libsqlite3-dev; without them open() throws an InputError saying how to
// enable the format (bagSupportBuilt(), ros2BagSupportBuilt()).
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "flowfusion/core/camera.h"
#include "flowfusion/io/ros_images.h"
#include "flowfusion/io/ros_recording.h"
#include "flowfusion/io/tum_sequence.h"

namespace ff {

class BagReader {
 public:
  // Opens the bag, picks the topics (options.bag.rgb_topic/depth_topic, else the known names, else
  // the only image topic with / without "depth" in its name), reads the camera (options.camera,
  // else a TUM bag's name rgbd_dataset_freiburgN_*, else CameraInfo beside the colour topic or
  // the bag's only CameraInfo topic) and associates the stamps. Throws InputError naming the bag
  // and topic on a truncated or unreadable bag, missing topics, unknown encodings, unsorted
  // stamps or no associated pair.
  static BagReader open(const std::string& path, const SequenceOptions& options);
  BagReader(BagReader&&) noexcept;
  BagReader& operator=(BagReader&&) noexcept;
  ~BagReader();

  size_t size() const;
  // Decodes pair i (any order; forward reads are cheapest). Throws InputError on a message that
  // does not decode or whose size differs from the camera's.
  BagFrame read(size_t i);
  const CameraModel& camera() const;
  const std::string& path() const;
  const std::string& colorTopic() const;
  const std::string& depthTopic() const;

 private:
  struct Impl;
  explicit BagReader(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace ff
