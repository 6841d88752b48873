#pragma once
// Pinhole camera intrinsics and the Freiburg presets of the TUM RGB-D benchmark.
#include <Eigen/Core>
#include <optional>
#include <string>

namespace ff {

struct CameraIntrinsics {
  double fx = 0, fy = 0;  // focal lengths, pixels
  double cx = 0, cy = 0;  // principal point, pixels (pixel centres at integer coordinates)
  int width = 0, height = 0;  // image size, pixels

  // Pixel (u, v) and depth z (metres) to a 3D point in the camera frame (metres).
  Eigen::Vector3d backproject(double u, double v, double z) const {
    return {(u - cx) * z / fx, (v - cy) * z / fy, z};
  }
  // 3D point in the camera frame to pixel coordinates; the caller checks z > 0.
  Eigen::Vector2d project(const Eigen::Vector3d& p) const {
    return {fx * p.x() / p.z() + cx, fy * p.y() / p.z() + cy};
  }
  bool inImage(double u, double v) const {
    return u >= 0 && v >= 0 && u <= width - 1 && v <= height - 1;
  }
  // Intrinsics of an image downsampled by 2^level with 2x2 averaging (pixel centres move).
  CameraIntrinsics atLevel(int level) const;
  Eigen::Matrix3d K() const;
  bool valid() const { return fx > 0 && fy > 0 && width > 0 && height > 0; }
};

// "fr1", "fr2", "fr3" (TUM RGB-D benchmark, 640x480) or "fx,fy,cx,cy" (640x480 unless
// "fx,fy,cx,cy,width,height"). Throws InputError naming `what` on anything else.
CameraIntrinsics parseCamera(const std::string& spec, const std::string& what = "--camera");
std::optional<CameraIntrinsics> freiburgPreset(int n);

}  // namespace ff
