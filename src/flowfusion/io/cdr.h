#pragma once
// CDR (XCDR1, the encoding ROS 2 messages are stored in): a reader over one serialized message,
// little or big endian as its 4-byte encapsulation header says, and the sensor_msgs/msg messages
// an RGB-D recording holds. Every read is bounds-checked: a short or malformed message is a
// CdrError saying what ran out, never a read past the buffer.
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "flowfusion/io/ros_recording.h"

namespace ff {

class CdrError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class CdrReader {
 public:
  // Reads the encapsulation header (CDR_BE or CDR_LE); throws CdrError on any other kind (XCDR2,
  // parameter lists) or a message shorter than it.
  CdrReader(const uint8_t* data, size_t size);
  uint8_t u8();
  uint32_t u32();
  int32_t i32() { return static_cast<int32_t>(u32()); }
  double f64();
  std::string string();  // uint32 length with the terminating NUL, then the bytes
  // A uint8[] sequence as a view into the message.
  const uint8_t* bytes(size_t& count);
  std::vector<double> f64Sequence();
  bool bigEndian() const { return big_endian_; }

 private:
  void align(size_t n);
  const uint8_t* take(size_t n, const char* what);
  const uint8_t* data_;  // the payload after the encapsulation header (alignment origin)
  size_t size_;
  size_t pos_ = 0;
  bool big_endian_ = false;
};

// sensor_msgs/msg/Image, CompressedImage and CameraInfo from their CDR bytes; an image's data is
// a view into `data`. Throws CdrError.
RosImage decodeRos2Image(const uint8_t* data, size_t size);
RosImage decodeRos2CompressedImage(const uint8_t* data, size_t size);
RosCameraInfo decodeRos2CameraInfo(const uint8_t* data, size_t size);

}  // namespace ff
