#pragma once
// A tiny analytic RGB-D scene for the flow and segmentation tests and benchmarks: a textured
// back wall and a textured box in front of it, ray cast exactly (no noise, no holes), so the
// true flow of static pixels is egoFlow() of the true depth. World frame = camera A's frame.
#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "flowfusion/core/camera.h"
#include "flowfusion/core/rgbd_frame.h"
#include "flowfusion/core/se3.h"

namespace ff::testing {

// Smooth 3D value noise in [0, 1], a few octaves, deterministic.
inline float valueNoise3(const Eigen::Vector3d& p) {
  auto hash = [](int x, int y, int z) {
    std::uint32_t h = static_cast<std::uint32_t>(x) * 73856093u ^ static_cast<std::uint32_t>(y) * 19349663u ^
                      static_cast<std::uint32_t>(z) * 83492791u;
    h ^= h >> 13;
    h *= 0x5bd1e995u;
    h ^= h >> 15;
    return (h & 0xffffu) / 65535.f;
  };
  float sum = 0, amp = 0.5f, norm = 0;
  double freq = 4.0;  // cycles per metre at the first octave (finest ~10 px per cycle at 640x480)
  for (int o = 0; o < 3; ++o, amp *= 0.5f, freq *= 2.1) {
    const Eigen::Vector3d q = p * freq;
    const int x0 = static_cast<int>(std::floor(q.x())), y0 = static_cast<int>(std::floor(q.y())),
              z0 = static_cast<int>(std::floor(q.z()));
    const double fx = q.x() - x0, fy = q.y() - y0, fz = q.z() - z0;
    auto s = [](double t) { return t * t * (3 - 2 * t); };
    const double sx = s(fx), sy = s(fy), sz = s(fz);
    float v = 0;
    for (int c = 0; c < 8; ++c) {
      const int dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
      const double w = (dx ? sx : 1 - sx) * (dy ? sy : 1 - sy) * (dz ? sz : 1 - sz);
      v += static_cast<float>(w) * hash(x0 + dx, y0 + dy, z0 + dz);
    }
    sum += amp * v;
    norm += amp;
  }
  return sum / norm;
}

struct AnalyticView {
  RgbdFrame frame;  // intensity and depth (colour = grey)
  cv::Mat mask;     // CV_8U, 255 on the box
};

struct AnalyticScene {
  CameraIntrinsics camera;
  double wall_z = 3.0;                              // m, the wall plane z = wall_z (world)
  Eigen::Vector3d box_centre{0.25, 0.05, 1.5};      // m, world, at box offset 0
  Eigen::Vector3d box_half{0.25, 0.3, 0.2};         // m

  // fr1 intrinsics scaled to width x height.
  static AnalyticScene make(int width, int height) {
    AnalyticScene s;
    const double k = width / 640.0;
    s.camera = CameraIntrinsics{517.3 * k, 516.5 * k, 318.6 * k, 255.3 * k, width, height};
    return s;
  }

  // Renders from T_world_cam with the box translated by box_offset (m, world). The box's texture
  // moves with it.
  AnalyticView render(const SE3& T_world_cam, const Eigen::Vector3d& box_offset = Eigen::Vector3d::Zero()) const {
    AnalyticView out;
    out.frame.depth = cv::Mat(camera.height, camera.width, CV_32F, cv::Scalar(0));
    out.frame.intensity = cv::Mat(camera.height, camera.width, CV_32F, cv::Scalar(0));
    out.mask = cv::Mat(camera.height, camera.width, CV_8U, cv::Scalar(0));
    const Eigen::Matrix3d R = T_world_cam.rotation();
    const Eigen::Vector3d o = T_world_cam.translation();
    const Eigen::Vector3d lo = box_centre + box_offset - box_half, hi = box_centre + box_offset + box_half;
    cv::parallel_for_(cv::Range(0, camera.height), [&](const cv::Range& rows) {
      for (int v = rows.start; v < rows.end; ++v)
        for (int u = 0; u < camera.width; ++u) {
          const Eigen::Vector3d d_cam((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, 1.0);
          const Eigen::Vector3d d = R * d_cam;
          // Ray parameter t along d_cam equals the camera-frame depth.
          double t_best = std::numeric_limits<double>::infinity();
          Eigen::Vector3d tex_point = Eigen::Vector3d::Zero();
          bool on_box = false;
          if (std::abs(d.z()) > 1e-9) {
            const double t = (wall_z - o.z()) / d.z();
            if (t > 0) {
              t_best = t;
              tex_point = o + t * d;
            }
          }
          double tmin = 0, tmax = std::numeric_limits<double>::infinity();
          bool hit = true;
          for (int a = 0; a < 3 && hit; ++a) {
            if (std::abs(d[a]) < 1e-12) {
              hit = o[a] >= lo[a] && o[a] <= hi[a];
              continue;
            }
            double t0 = (lo[a] - o[a]) / d[a], t1 = (hi[a] - o[a]) / d[a];
            if (t0 > t1) std::swap(t0, t1);
            tmin = std::max(tmin, t0);
            tmax = std::min(tmax, t1);
            hit = tmin <= tmax;
          }
          if (hit && tmin > 0 && tmin < t_best) {
            t_best = tmin;
            tex_point = o + tmin * d - box_offset + Eigen::Vector3d(7.3, 1.1, 3.7);
            on_box = true;
          }
          if (!std::isfinite(t_best)) continue;
          out.frame.depth.at<float>(v, u) = static_cast<float>(t_best);
          out.frame.intensity.at<float>(v, u) = 0.1f + 0.8f * valueNoise3(tex_point);
          if (on_box) out.mask.at<uchar>(v, u) = 255;
        }
    });
    cv::Mat grey8;
    out.frame.intensity.convertTo(grey8, CV_8U, 255.0);
    cv::Mat channels[3] = {grey8, grey8, grey8};
    cv::merge(channels, 3, out.frame.color);
    return out;
  }
};

}  // namespace ff::testing
