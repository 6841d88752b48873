#pragma once
// sensor_msgs images and CameraInfo as flowfusion reads them, written once for the bags
// (io/bag_reader.h) and the live ROS node (ros/): which encodings a colour or depth image may have,
// their pixels decoded and checked against the camera, a CameraInfo as a camera model, a stamp as
// seconds, and an associated colour-depth pair as the RgbdFrame every source hands out.
#include <optional>
#include <string>

#include "flowfusion/core/camera.h"
#include "flowfusion/core/rgbd_frame.h"
#include "flowfusion/core/undistortion.h"
#include "flowfusion/io/ros_recording.h"

namespace ff {

// One associated colour-depth pair as it came (before any undistortion).
struct BagFrame {
  double timestamp = 0;        // s, the colour message's header stamp
  double depth_timestamp = 0;  // s, the depth message's header stamp
  cv::Mat bgr8;                // CV_8UC3
  cv::Mat depth;               // CV_16UC1 raw units (depth_scale per metre) or CV_32FC1 metres
  double depth_scale = 1;      // raw units per metre of a CV_16UC1 depth; 1 for metres
  std::string name;            // "BAG:TOPIC#INDEX" of the colour message, for messages
};

enum class RosImageKind { kColor, kDepth };

// The stamp as the decimal number it is ("sec.nnnnnnnnn" parsed), so that a stamp written to a
// TUM list with %.6f reads back as the same double.
double rosSeconds(const RosStamp& t);

// Why an image of this encoding (Image.encoding, or CompressedImage.format when `compressed`)
// cannot be read as `kind`, or "" when it can: colour rgb8, bgr8, mono8, rgba8, bgra8 or png/jpeg;
// depth 16UC1, mono16 or 32FC1.
std::string rosEncodingProblem(bool compressed, const std::string& encoding, RosImageKind kind);

// The colour image as CV_8UC3 BGR. Throws InputError starting with `name` on an encoding
// rosEncodingProblem refuses, a message shorter than it declares, or a size other than the camera's.
cv::Mat decodeRosColor(const RosImage& m, const std::string& name, const CameraIntrinsics& camera);
// The depth image: 16UC1/mono16 as CV_16UC1 with `units_per_metre` put in `scale`, 32FC1 as
// CV_32FC1 metres (NaN, inf and negatives as 0, no measurement) with scale 1. Throws as decodeRosColor.
cv::Mat decodeRosDepth(const RosImage& m, const std::string& name, const CameraIntrinsics& camera,
                       double units_per_metre, double& scale);

// The camera a CameraInfo describes (K, size, plumb-bob distortion or a rational polynomial
// without its extra terms). Throws InputError starting with `where` on another distortion model or
// unusable values, saying to give the camera instead.
CameraModel cameraModelFromInfo(const RosCameraInfo& info, const std::string& where);

// The pair as a frame in pinhole pixels: undistorted when `undistorter` is given, the depth in
// metres, the colour and depth times kept.
RgbdFrame rgbdFrameOf(const BagFrame& raw, const Undistorter* undistorter);

}  // namespace ff
