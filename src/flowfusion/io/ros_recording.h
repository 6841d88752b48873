#pragma once
// A recording of ROS messages as BagReader (io/bag_reader.h) reads it: its topics, one pass over
// the image messages of two topics, one image message again by its index, and a topic's first
// CameraInfo. Each format implements the container and the message parsing (a ROS 1 bag through
// Debian's rosbag in ros1_recording.cpp; a ROS 2 bag's MCAP or sqlite files with CDR messages in
// ros2_recording.cpp); topic discovery, encodings, pixels, stamps, camera and association are
// BagReader's, written once for both. Messages are handed out as views into the recording's
// buffers, so memory stays that of a chunk or two however long the recording is.
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace ff {

enum class RosType { kImage, kCompressedImage, kCameraInfo, kOther };

struct RosTopic {
  std::string name;
  std::string datatype;  // as recorded: sensor_msgs/Image (ROS 1), sensor_msgs/msg/Image (ROS 2)
  RosType type = RosType::kOther;
};

// A header stamp as recorded: whole seconds and nanoseconds.
struct RosStamp {
  int64_t sec = 0;
  uint32_t nsec = 0;
};

// A sensor_msgs Image or CompressedImage; `data` stays valid while `keep` is held.
struct RosImage {
  RosStamp stamp;
  bool compressed = false;
  std::string encoding;                      // Image.encoding, or CompressedImage.format
  uint32_t width = 0, height = 0, step = 0;  // pixels, pixels, bytes per row (Image only)
  bool big_endian = false;                   // Image.is_bigendian
  const uint8_t* data = nullptr;
  size_t size = 0;                           // bytes at data
  std::shared_ptr<const void> keep;          // owner of the bytes at data
};

// The parts of a sensor_msgs CameraInfo the camera model needs.
struct RosCameraInfo {
  uint32_t width = 0, height = 0;  // pixels
  std::string distortion_model;
  std::vector<double> d;           // distortion coefficients
  std::array<double, 9> k{};       // row-major intrinsic matrix, pixels
};

class RosRecording {
 public:
  virtual ~RosRecording() = default;
  // Every topic with its message type; a topic recorded with two types is listed twice.
  virtual std::vector<RosTopic> topics() = 0;
  // The messages on `topics` (image topics), each decoded once in the recording's order:
  // visit(index into topics, message). Remembers where each is for image(). Throws InputError
  // naming the file and topic on a message or container that does not decode.
  virtual void scanImages(const std::vector<std::string>& topics,
                          const std::function<void(size_t, const RosImage&)>& visit) = 0;
  // Message `index` of topics[slot] of the last scanImages (any order; forward reads cheapest).
  virtual RosImage image(size_t slot, size_t index) = 0;
  // The first CameraInfo on `topic`; nullopt when it has none.
  virtual std::optional<RosCameraInfo> firstCameraInfo(const std::string& topic) = 0;
};

// Whether this build reads ROS 1 bags (Debian's librosbag-storage-dev) and ROS 2 bags (our
// MCAP and sqlite readers over libzstd, liblz4 and libsqlite3).
bool bagSupportBuilt();
bool ros2BagSupportBuilt();

// A ROS 2 bag by its path: a .mcap or .db3 file, or a folder holding metadata.yaml.
bool isRos2BagPath(const std::string& path);

// The recording at `path`: a ROS 2 bag when isRos2BagPath, else a ROS 1 bag. Throws InputError
// naming the path when it is unreadable, or saying how to enable the format in a build without it.
std::unique_ptr<RosRecording> openRosRecording(const std::string& path);

// The formats' own openers (ros1_recording.cpp, ros2_recording.cpp).
std::unique_ptr<RosRecording> openRos1Recording(const std::string& path);
std::unique_ptr<RosRecording> openRos2Recording(const std::string& path);

}  // namespace ff
