#pragma once
// Pinhole camera intrinsics, lens distortion and the Freiburg presets of the TUM RGB-D benchmark.
// Every stage works with the pinhole model; a sequence with lens distortion is undistorted when
// its frames are loaded (core/undistortion.h).
#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

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

// Radial (k1, k2, k3) and tangential (p1, p2) coefficients of the Brown-Conrady model, in
// OpenCV's order and convention; all zero = a pinhole lens.
struct LensDistortion {
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0, k3 = 0;
  bool none() const { return k1 == 0 && k2 == 0 && p1 == 0 && p2 == 0 && k3 == 0; }
};

struct CameraModel {
  CameraIntrinsics intrinsics;
  LensDistortion distortion;
};

// "fr1", "fr2", "fr3" (TUM RGB-D benchmark, 640x480, with the benchmark's distortion
// coefficients) or "fx,fy,cx,cy" (640x480 unless "fx,fy,cx,cy,width,height"; distortion
// coefficients may follow the size: "...,width,height,k1,k2,p1,p2,k3"). Throws InputError naming
// `what` on anything else.
CameraModel parseCameraModel(const std::string& spec, const std::string& what = "--camera");
// The model from fx, fy, cx, cy[, width, height[, k1, k2, p1, p2, k3]] (640x480 when the size is
// left out); the caller checks the values with cameraValuesProblem first. Throws
// std::invalid_argument (a programming mistake) on any other count.
CameraModel cameraModelFromValues(const std::vector<double>& values);
// What is wrong with such values, or nullopt when they are usable: focal lengths 1..1e6 pixels,
// a size of 1..100000 pixels a side (whole numbers), the principal point within one image size
// of the image, distortion coefficients within +-1000, everything finite.
std::optional<std::string> cameraValuesProblem(const std::vector<double>& values);
CameraIntrinsics parseCamera(const std::string& spec, const std::string& what = "--camera");
std::optional<CameraIntrinsics> freiburgPreset(int n);
// The benchmark's published coefficients of the colour camera (the depth images are registered
// to it, so they share them); fr3's images were undistorted before publication (zero).
std::optional<LensDistortion> freiburgDistortion(int n);

}  // namespace ff
