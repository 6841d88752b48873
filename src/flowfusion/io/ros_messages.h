#pragma once
// The ROS 1 messages a bag's RGB-D frames come in, for code built with Debian's rosbag and
// sensor_msgs headers (FLOWFUSION_HAVE_ROSBAG: io/bag_reader.cpp, the bag tests and benchmark).
// The generated message headers rebind std::allocator<void>, which C++20 removed; the messages are
// templates on their allocator, so they are used with one that still rebinds.
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>

#include <memory>

namespace ff::ros1 {

template <class T>
struct RosAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = RosAllocator<U>;
  };
  RosAllocator() = default;
  template <class U>
  RosAllocator(const RosAllocator<U>&) {}
};

using ImageMsg = sensor_msgs::Image_<RosAllocator<void>>;
using CompressedImageMsg = sensor_msgs::CompressedImage_<RosAllocator<void>>;
using CameraInfoMsg = sensor_msgs::CameraInfo_<RosAllocator<void>>;

}  // namespace ff::ros1
