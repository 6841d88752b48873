#include "flowfusion/io/ros_images.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "flowfusion/core/error.h"
#include "flowfusion/core/image_file.h"

namespace ff {

namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

// The pixels of a raw image message (rows `step` bytes apart), copied; InputError when the
// message holds fewer bytes than it declares.
cv::Mat wrapImage(const RosImage& m, int type, const std::string& name) {
  const size_t row = size_t(m.width) * CV_ELEM_SIZE(type);
  if (m.width == 0 || m.height == 0 || m.step < row || m.size < size_t(m.step) * m.height ||
      static_cast<long long>(m.width) * m.height > kMaxImagePixels)
    throw InputError(name + ": image message of " + std::to_string(m.width) + "x" + std::to_string(m.height) +
                     " (step " + std::to_string(m.step) + ") holds " + std::to_string(m.size) + " bytes");
  cv::Mat view(int(m.height), int(m.width), type, const_cast<uint8_t*>(m.data), m.step);
  cv::Mat out = view.clone();
  if (m.big_endian && CV_ELEM_SIZE1(type) > 1) {
    // Multi-byte samples stored big-endian: reverse each sample's bytes.
    const size_t n = CV_ELEM_SIZE1(type);
    for (int y = 0; y < out.rows; ++y)
      for (uint8_t* p = out.ptr<uint8_t>(y); p < out.ptr<uint8_t>(y) + row; p += n) std::reverse(p, p + n);
  }
  return out;
}

cv::Mat toBgr(const cv::Mat& image, const std::string& name) {
  if (image.depth() != CV_8U) throw InputError(name + ": colour image must be 8-bit per channel");
  cv::Mat bgr;
  if (image.channels() == 1) cv::cvtColor(image, bgr, cv::COLOR_GRAY2BGR);
  else if (image.channels() == 4) cv::cvtColor(image, bgr, cv::COLOR_BGRA2BGR);
  else bgr = image;
  return bgr;
}

std::string sizeMismatch(const std::string& name, long long w, long long h, const CameraIntrinsics& c) {
  return name + ": image is " + std::to_string(w) + "x" + std::to_string(h) + ", the camera is " +
         std::to_string(c.width) + "x" + std::to_string(c.height);
}

void checkSize(const cv::Mat& image, const std::string& name, const CameraIntrinsics& c) {
  if (image.cols != c.width || image.rows != c.height) throw InputError(sizeMismatch(name, image.cols, image.rows, c));
}

// A compressed colour image decoded; a PNG declares its size before any pixel is decoded
// (image_file.h), so a wrong one is refused there.
cv::Mat decodeCompressed(const RosImage& m, const std::string& name, const CameraIntrinsics& c) {
  const uint8_t* d = m.data;
  if (m.size >= 24 && d[1] == 'P' && d[2] == 'N' && d[3] == 'G') {
    const auto be32 = [&](size_t at) {
      return uint32_t(d[at]) << 24 | uint32_t(d[at + 1]) << 16 | uint32_t(d[at + 2]) << 8 | uint32_t(d[at + 3]);
    };
    if (be32(16) != uint32_t(c.width) || be32(20) != uint32_t(c.height))
      throw InputError(sizeMismatch(name, be32(16), be32(20), c));
  }
  cv::Mat decoded;
  if (m.size > 0 && m.size < size_t(INT32_MAX)) {
    const cv::Mat bytes(1, int(m.size), CV_8U, const_cast<uint8_t*>(d));
    try {
      decoded = cv::imdecode(bytes, cv::IMREAD_UNCHANGED);
    } catch (const cv::Exception&) {
    }
  }
  if (decoded.empty()) throw InputError(name + ": compressed image (" + m.encoding + ") does not decode");
  return toBgr(decoded, name);
}

}  // namespace

double rosSeconds(const RosStamp& t) {
  char buf[48];
  std::snprintf(buf, sizeof(buf), "%lld.%09u", static_cast<long long>(t.sec), t.nsec);
  return std::strtod(buf, nullptr);
}

std::string rosEncodingProblem(bool compressed, const std::string& encoding, RosImageKind kind) {
  const std::string e = lower(encoding);
  if (compressed) {
    if (e.find("compresseddepth") != std::string::npos)
      return "compressedDepth images are not supported (record the raw depth topic)";
    if (kind == RosImageKind::kDepth) return "depth must be a raw sensor_msgs/Image (16UC1, mono16 or 32FC1)";
    if (e.find("png") == std::string::npos && e.find("jpeg") == std::string::npos &&
        e.find("jpg") == std::string::npos)
      return "compressed format '" + encoding + "' is not png or jpeg";
    return "";
  }
  if (kind == RosImageKind::kColor) {
    if (e == "rgb8" || e == "bgr8" || e == "mono8" || e == "rgba8" || e == "bgra8") return "";
    return "colour encoding '" + encoding + "' is not one of rgb8, bgr8, mono8, rgba8, bgra8";
  }
  if (e == "16uc1" || e == "mono16" || e == "32fc1") return "";
  return "depth encoding '" + encoding + "' is not one of 16UC1, mono16, 32FC1";
}

cv::Mat decodeRosColor(const RosImage& m, const std::string& name, const CameraIntrinsics& camera) {
  cv::Mat bgr;
  if (m.compressed) {
    bgr = decodeCompressed(m, name, camera);
  } else {
    const std::string e = lower(m.encoding);
    if (e == "rgb8") cv::cvtColor(wrapImage(m, CV_8UC3, name), bgr, cv::COLOR_RGB2BGR);
    else if (e == "bgr8") bgr = wrapImage(m, CV_8UC3, name);
    else if (e == "mono8") cv::cvtColor(wrapImage(m, CV_8UC1, name), bgr, cv::COLOR_GRAY2BGR);
    else if (e == "rgba8") cv::cvtColor(wrapImage(m, CV_8UC4, name), bgr, cv::COLOR_RGBA2BGR);
    else if (e == "bgra8") cv::cvtColor(wrapImage(m, CV_8UC4, name), bgr, cv::COLOR_BGRA2BGR);
    else throw InputError(name + ": " + rosEncodingProblem(false, m.encoding, RosImageKind::kColor));
  }
  checkSize(bgr, name, camera);
  return bgr;
}

cv::Mat decodeRosDepth(const RosImage& m, const std::string& name, const CameraIntrinsics& camera,
                       double units_per_metre, double& scale) {
  const std::string e = lower(m.encoding);
  cv::Mat depth;
  if (!m.compressed && (e == "16uc1" || e == "mono16")) {
    depth = wrapImage(m, CV_16UC1, name);
    scale = units_per_metre;
  } else if (!m.compressed && e == "32fc1") {
    depth = wrapImage(m, CV_32FC1, name);
    // No measurement is 0 in every stage; ROS drivers write NaN (and some +-inf or negatives).
    depth.forEach<float>([](float& d, const int*) {
      if (!std::isfinite(d) || d < 0) d = 0;
    });
    scale = 1;
  } else {
    throw InputError(name + ": " + rosEncodingProblem(m.compressed, m.encoding, RosImageKind::kDepth));
  }
  checkSize(depth, name, camera);
  return depth;
}

CameraModel cameraModelFromInfo(const RosCameraInfo& info, const std::string& where) {
  std::vector<double> v = {info.k[0], info.k[4], info.k[2], info.k[5], double(info.width), double(info.height)};
  const std::string& model = info.distortion_model;
  const std::vector<double>& d = info.d;
  bool distorted = false;
  for (double k : d) distorted = distorted || k != 0;
  if (distorted) {
    if (model != "plumb_bob" && !(model == "rational_polynomial" && d.size() >= 8 && d[5] == 0 && d[6] == 0 && d[7] == 0))
      throw InputError(where + ": distortion model '" + model +
                       "' is not supported (plumb_bob); give --camera or --no-undistort");
    for (size_t k = 0; k < 5; ++k) v.push_back(k < d.size() ? d[k] : 0.0);
  }
  if (const auto problem = cameraValuesProblem(v)) throw InputError(where + ": " + *problem + "; give --camera");
  return cameraModelFromValues(v);
}

RgbdFrame rgbdFrameOf(const BagFrame& raw, const Undistorter* undistorter) {
  cv::Mat color = raw.bgr8, depth = raw.depth;
  if (undistorter) {
    color = undistorter->undistortColor(color);
    depth = undistorter->undistortDepth(depth);  // nearest: the same for raw units and metres
  }
  RgbdFrame frame;
  if (depth.type() == CV_16UC1) {
    frame = makeRgbdFrame(raw.timestamp, color, depth, raw.depth_scale, raw.name);
  } else {
    frame.timestamp = raw.timestamp;
    frame.color = color;
    frame.intensity = intensityFromBgr(color);
    frame.depth = depth;
    frame.name = raw.name;
  }
  frame.depth_timestamp = raw.depth_timestamp;
  return frame;
}

}  // namespace ff
