#pragma once
// What the node makes of one synchronised colour-depth pair (and the colour CameraInfo): the
// RgbdFrame a bag of the same messages gives (io/ros_images.h: the same decoding, depth units,
// camera and undistortion), or an InputError saying why the messages cannot be used: an encoding
// or size the frames cannot have, a colour stamp not after the last one taken, no camera yet.
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <ros/time.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <string>

#include "flowfusion/core/error.h"
#include "flowfusion/core/rgbd_frame.h"
#include "flowfusion/core/undistortion.h"
#include "flowfusion/ros/node_params.h"

namespace ff::rosnode {

// A taken frame's colour header, to stamp what is published about it.
struct ColorHeader {
  ros::Time stamp;
  std::string frame_id;
};

// A colour stamp not after the last frame's; its message names the stamps, so the node logs the
// kind once rather than each message.
struct StampsGoingBack : InputError {
  using InputError::InputError;
};

class FrameIntake {
 public:
  explicit FrameIntake(const NodeParams& params);

  // The frame of these messages; `info` is null when the camera was given. Throws InputError naming
  // the topic and the reason; a colour stamp not after the last one taken is refused until reset()
  // (StampsGoingBack).
  RgbdFrame take(const sensor_msgs::Image& color, const sensor_msgs::Image& depth, const sensor_msgs::CameraInfo* info);
  // The camera once known (given, or the first usable CameraInfo) and its undistortion (null: none).
  const std::optional<CameraModel>& camera() const { return camera_; }
  std::shared_ptr<const Undistorter> undistorter() const { return undistorter_; }
  // The colour header of a frame taken lately, by its timestamp (any thread).
  std::optional<ColorHeader> headerOf(double timestamp) const;
  // Forgets the last stamp (a new run may start earlier, as a bag played again).
  void reset();

 private:
  void learnCamera(const sensor_msgs::CameraInfo& info);

  const NodeParams& params_;
  std::optional<CameraModel> camera_;
  std::shared_ptr<const Undistorter> undistorter_;
  std::optional<ros::Time> last_stamp_;
  mutable std::mutex headers_mutex_;
  std::map<double, ColorHeader> headers_;  // the last few taken frames'
};

}  // namespace ff::rosnode
