// The 3D view's data: the map's points (subsampled, 16-bit quantised), camera path, keyframes.
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "flowfusion/fusion/map_compare.h"
#include "flowfusion/report/report_parts.h"

namespace ff::report {
namespace {

constexpr double kKeyframeMinRotationDeg = 10;  // a frustum every 10 degrees of turn ...
constexpr double kKeyframeMinTravelFraction = 0.02;  // ... or 2% of the map's extent of travel
constexpr size_t kMaxKeyframes = 60;

nlohmann::json xyz(const Eigen::Vector3d& p) {
  return {std::round(p.x() * 1e4) / 1e4, std::round(p.y() * 1e4) / 1e4, std::round(p.z() * 1e4) / 1e4};
}

// Every stride-th point, quantised to int16 within the box [lo, hi] (little-endian x, y, z).
std::string quantise(const std::vector<Eigen::Vector3f>& points, size_t stride, const Eigen::Vector3f& lo,
                     const Eigen::Vector3f& hi) {
  std::string bytes;
  const Eigen::Vector3f scale = (hi - lo).cwiseMax(1e-6f);
  for (size_t i = 0; i < points.size(); i += stride)
    for (int a = 0; a < 3; ++a) {
      const float u = std::clamp((points[i][a] - lo[a]) / scale[a], 0.0f, 1.0f);
      const auto q = static_cast<int16_t>(std::lround(u * 65535.0f) - 32768);
      const auto uq = static_cast<uint16_t>(q);
      bytes.push_back(static_cast<char>(uq & 0xff));
      bytes.push_back(static_cast<char>(uq >> 8));
    }
  return bytes;
}

// Poses where a frustum is drawn: the first, then each one that turned or travelled enough since.
nlohmann::json keyframes(const Trajectory& est, double extent_m) {
  nlohmann::json out = nlohmann::json::array();
  if (est.empty()) return out;
  const double min_travel = kKeyframeMinTravelFraction * extent_m;
  const SE3* last = nullptr;
  for (const auto& p : est) {
    if (last) {
      const SE3 d = last->inverse() * p.T_world_cam;
      if (translationNorm(d) < min_travel && rotationAngleDeg(d) < kKeyframeMinRotationDeg) continue;
    }
    last = &p.T_world_cam;
    nlohmann::json m = nlohmann::json::array();  // column-major 4x4, as THREE.Matrix4.fromArray
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) m.push_back(std::round(p.T_world_cam.matrix()(r, c) * 1e5) / 1e5);
    out.push_back(std::move(m));
  }
  if (out.size() > kMaxKeyframes) {
    nlohmann::json thinned = nlohmann::json::array();
    for (size_t k = 0; k < kMaxKeyframes; ++k) thinned.push_back(out[k * out.size() / kMaxKeyframes]);
    return thinned;
  }
  return out;
}

}  // namespace

std::string base64(std::string_view bytes) {
  static constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (size_t i = 0; i < bytes.size(); i += 3) {
    const size_t n = std::min<size_t>(3, bytes.size() - i);
    uint32_t v = 0;
    for (size_t k = 0; k < 3; ++k) v = (v << 8) | (k < n ? static_cast<unsigned char>(bytes[i + k]) : 0u);
    for (size_t k = 0; k < 4; ++k) out.push_back(k <= n ? kAlphabet[(v >> (18 - 6 * k)) & 63] : '=');
  }
  return out;
}

nlohmann::json mapSection(const std::string& ply_path, size_t max_points, const Trajectory& est,
                          const std::vector<Eigen::Vector3d>& gt_path_in_map) {
  const std::vector<Eigen::Vector3f> points = readMapPoints(ply_path);
  Eigen::Vector3f lo = points.front(), hi = points.front();
  for (const auto& p : points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const size_t stride = std::max<size_t>(1, (points.size() + max_points - 1) / std::max<size_t>(max_points, 1));
  nlohmann::json j;
  j["total"] = points.size();
  j["count"] = (points.size() + stride - 1) / stride;
  j["lo"] = {lo.x(), lo.y(), lo.z()};
  j["hi"] = {hi.x(), hi.y(), hi.z()};
  j["points_int16"] = base64(quantise(points, stride, lo, hi));
  j["path"] = nlohmann::json::array();
  for (const auto& p : est) j["path"].push_back(xyz(p.T_world_cam.translation()));
  j["gt_path"] = nlohmann::json::array();
  for (const auto& p : gt_path_in_map) j["gt_path"].push_back(xyz(p));
  j["keyframes"] = keyframes(est, (hi - lo).cast<double>().norm());
  // The average of the cameras' up direction (-y in the camera frame) is "up" in the view.
  Eigen::Vector3d up = Eigen::Vector3d::Zero();
  for (const auto& p : est) up += p.T_world_cam.rotation() * Eigen::Vector3d(0, -1, 0);
  if (up.norm() < 1e-9) up = Eigen::Vector3d::UnitZ();
  j["up"] = xyz(up.normalized());
  return j;
}

}  // namespace ff::report
