#pragma once
// An analytic scene for the fusion tests: a textured box room seen from inside, optionally with a
// sphere moving along a straight line. Depth, colour and the sphere's mask are exact, so the true
// geometry is known everywhere (distance to the room's planes, the sphere's swept capsule).
#include <opencv2/core.hpp>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "flowfusion/core/camera.h"
#include "flowfusion/core/rgbd_frame.h"
#include "flowfusion/core/se3.h"

namespace ff::testing {

struct RoomFixture {
  // Room: x in [-2, 2], y in [-1.5, 1.5] (y down, floor at +1.5), z in [-1, 4], metres.
  Eigen::Vector3d room_min{-2.0, -1.5, -1.0};
  Eigen::Vector3d room_max{2.0, 1.5, 4.0};
  bool with_sphere = false;
  double sphere_radius_m = 0.3;
  Eigen::Vector3d sphere_start{-0.6, 0.2, 2.0};
  Eigen::Vector3d sphere_end{0.6, 0.2, 2.0};
  int frames = 40;
  CameraIntrinsics camera{262.0, 262.0, 159.5, 119.5, 320, 240};

  // A gentle hand-held-like path looking down +z; the sphere stays in view (free space can only be
  // observed where the camera looks).
  SE3 pose(int i) const {
    const double s = static_cast<double>(i) / std::max(1, frames - 1);
    SE3 T = SE3::Identity();
    T.linear() = (Eigen::AngleAxisd(0.08 * std::sin(3.0 * s), Eigen::Vector3d::UnitY()) *
                  Eigen::AngleAxisd(0.05 * std::cos(2.0 * s), Eigen::Vector3d::UnitX()))
                     .toRotationMatrix();
    T.translation() = Eigen::Vector3d(0.3 * std::sin(2.0 * s), 0.1 * std::cos(3.0 * s) - 0.1, 0.2 * s);
    return T;
  }
  Eigen::Vector3d sphereCentre(int i) const {
    const double s = static_cast<double>(i) / std::max(1, frames - 1);
    return sphere_start + s * (sphere_end - sphere_start);
  }

  // Distance of a world point to the nearest room wall, metres.
  double distanceToRoom(const Eigen::Vector3d& p) const {
    const Eigen::Vector3d a = (p - room_min).cwiseAbs(), b = (room_max - p).cwiseAbs();
    return std::min(a.minCoeff(), b.minCoeff());
  }
  // Mean of distanceToRoom over `points` (a mesh's vertices).
  double meanDistanceToRoom(const std::vector<Eigen::Vector3d>& points) const {
    double sum = 0;
    for (const auto& p : points) sum += distanceToRoom(p);
    return sum / points.size();
  }
  // Distance from the segment the sphere's centre travels; below the radius = inside the swept volume.
  double distanceToSweep(const Eigen::Vector3d& p) const {
    const Eigen::Vector3d d = sphere_end - sphere_start;
    const double s = std::clamp((p - sphere_start).dot(d) / d.squaredNorm(), 0.0, 1.0);
    return (p - (sphere_start + s * d)).norm();
  }

  static cv::Vec3b texture(const Eigen::Vector3d& p) {
    const int cell = static_cast<int>(std::floor(p.x() * 4) + std::floor(p.y() * 4) + std::floor(p.z() * 4));
    const double g = 0.5 + 0.25 * std::sin(7.0 * p.x() + 3.0 * p.y()) + 0.15 * std::cos(5.0 * p.z());
    const uchar v = cv::saturate_cast<uchar>(255.0 * std::clamp(g * ((cell & 1) ? 1.0 : 0.6), 0.0, 1.0));
    return cv::Vec3b(v, static_cast<uchar>(v * 0.8), static_cast<uchar>(255 - v / 2));
  }

  struct View {
    RgbdFrame frame;
    cv::Mat mask;  // CV_8UC1, 255 on the sphere
  };
  // Renders frame i (sphere at its position of frame i) or, with sphere_at < 0, without sphere.
  View render(const SE3& T_world_cam, const CameraIntrinsics& cam, int sphere_at) const {
    View v;
    cv::Mat color(cam.height, cam.width, CV_8UC3, cv::Scalar(0, 0, 0));
    v.frame.depth = cv::Mat::zeros(cam.height, cam.width, CV_32FC1);
    v.mask = cv::Mat::zeros(cam.height, cam.width, CV_8UC1);
    const Eigen::Vector3d o = T_world_cam.translation();
    const Eigen::Vector3d c = sphere_at >= 0 ? sphereCentre(sphere_at) : Eigen::Vector3d::Zero();
    for (int y = 0; y < cam.height; ++y)
      for (int x = 0; x < cam.width; ++x) {
        // Ray with unit z in the camera frame: its parameter is the depth.
        const Eigen::Vector3d d = T_world_cam.linear() * Eigen::Vector3d((x - cam.cx) / cam.fx, (y - cam.cy) / cam.fy, 1);
        double t = std::numeric_limits<double>::max();
        for (int a = 0; a < 3; ++a)
          for (double plane : {room_min[a], room_max[a]}) {
            if (std::abs(d[a]) < 1e-12) continue;
            const double ta = (plane - o[a]) / d[a];
            if (ta > 0) t = std::min(t, ta);
          }
        bool on_sphere = false;
        if (with_sphere && sphere_at >= 0) {
          const Eigen::Vector3d oc = o - c;
          const double A = d.squaredNorm(), B = 2 * oc.dot(d), C = oc.squaredNorm() - sphere_radius_m * sphere_radius_m;
          const double disc = B * B - 4 * A * C;
          if (disc >= 0) {
            const double ts = (-B - std::sqrt(disc)) / (2 * A);
            if (ts > 0 && ts < t) {
              t = ts;
              on_sphere = true;
            }
          }
        }
        const Eigen::Vector3d p = o + t * d;
        v.frame.depth.at<float>(y, x) = static_cast<float>(t);
        color.at<cv::Vec3b>(y, x) = on_sphere ? cv::Vec3b(40, 200, 40) : texture(p);
        if (on_sphere) v.mask.at<uchar>(y, x) = 255;
      }
    v.frame.color = color;
    v.frame.intensity = intensityFromBgr(color);
    v.frame.name = "room";
    return v;
  }
  View render(int i) const { return render(pose(i), camera, i); }
};

}  // namespace ff::testing
