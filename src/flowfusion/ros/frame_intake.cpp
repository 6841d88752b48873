#include "flowfusion/ros/frame_intake.h"

#include "flowfusion/io/ros_images.h"
#include "flowfusion/io/tum_sequence.h"

namespace ff::rosnode {

namespace {

constexpr size_t kKeptHeaders = 64;  // frames taken and not yet published are at most two

RosImage viewOf(const sensor_msgs::Image& m) {
  RosImage r;
  r.stamp = {m.header.stamp.sec, m.header.stamp.nsec};
  r.encoding = m.encoding;
  r.width = m.width;
  r.height = m.height;
  r.step = m.step;
  r.big_endian = m.is_bigendian != 0;
  r.data = m.data.data();
  r.size = m.data.size();
  return r;
}

double seconds(const ros::Time& t) { return rosSeconds({t.sec, t.nsec}); }

}  // namespace

FrameIntake::FrameIntake(const NodeParams& params) : params_(params), camera_(params.camera) {
  if (camera_ && params_.undistort && !camera_->distortion.none())
    undistorter_ = std::make_shared<Undistorter>(camera_->intrinsics, camera_->distortion);
}

void FrameIntake::learnCamera(const sensor_msgs::CameraInfo& info) {
  RosCameraInfo r;
  r.width = info.width;
  r.height = info.height;
  r.distortion_model = info.distortion_model;
  r.d.assign(info.D.begin(), info.D.end());
  std::copy(info.K.begin(), info.K.end(), r.k.begin());
  camera_ = cameraModelFromInfo(r, "CameraInfo");
  if (params_.undistort && !camera_->distortion.none())
    undistorter_ = std::make_shared<Undistorter>(camera_->intrinsics, camera_->distortion);
}

RgbdFrame FrameIntake::take(const sensor_msgs::Image& color, const sensor_msgs::Image& depth,
                            const sensor_msgs::CameraInfo* info) {
  if (!camera_) {
    if (!info) throw InputError("no camera: give ~camera or --camera, or the colour CameraInfo");
    learnCamera(*info);
  }
  if (last_stamp_ && !(color.header.stamp > *last_stamp_))
    throw StampsGoingBack("colour: header stamp " + timestampName(seconds(color.header.stamp)) +
                     " is not after the last frame's " + timestampName(seconds(*last_stamp_)) +
                     " (stamps going back: a bag played again or a clock reset?); frames are refused until they are "
                     "after it, or call ~reset");
  BagFrame raw;
  raw.timestamp = seconds(color.header.stamp);
  raw.depth_timestamp = seconds(depth.header.stamp);
  raw.name = "colour " + timestampName(raw.timestamp);
  raw.bgr8 = decodeRosColor(viewOf(color), "colour", camera_->intrinsics);
  raw.depth = decodeRosDepth(viewOf(depth), "depth", camera_->intrinsics, params_.depth_scale, raw.depth_scale);
  last_stamp_ = color.header.stamp;
  {
    std::lock_guard lock(headers_mutex_);
    headers_[raw.timestamp] = {color.header.stamp, color.header.frame_id};
    if (headers_.size() > kKeptHeaders) headers_.erase(headers_.begin());
  }
  return rgbdFrameOf(raw, undistorter_.get());
}

std::optional<ColorHeader> FrameIntake::headerOf(double timestamp) const {
  std::lock_guard lock(headers_mutex_);
  const auto it = headers_.find(timestamp);
  if (it == headers_.end()) return std::nullopt;
  return it->second;
}

void FrameIntake::reset() { last_stamp_.reset(); }

}  // namespace ff::rosnode
