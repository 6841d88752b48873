#include "flowfusion/fusion/static_map.h"

#include <spdlog/spdlog.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>

#include "flowfusion/core/error.h"

namespace ff {

namespace {

constexpr uint64_t kEmpty = std::numeric_limits<uint64_t>::max();

// Positive floats compare like their bit patterns, so (depth, index) packs into one integer whose
// minimum is the nearest surfel: a lock-free z-buffer.
uint64_t depthKey(float depth_m, uint32_t index) {
  return (static_cast<uint64_t>(std::bit_cast<uint32_t>(depth_m)) << 32) | index;
}
float keyDepth(uint64_t key) { return std::bit_cast<float>(static_cast<uint32_t>(key >> 32)); }
uint32_t keyIndex(uint64_t key) { return static_cast<uint32_t>(key & 0xffffffffu); }

// Nearest-surfel buffer of `pixels` keys, filled by splat(k, write) for every surfel k in
// parallel, write(pixel, key) keeping the minimum. Each thread fills its own buffer with plain
// stores and the buffers are merged at the end: a locked compare-exchange per write took a quarter
// of the rendering time.
template <class Splat>
std::vector<uint64_t> nearestSurfels(size_t surfels, size_t pixels, Splat&& splat) {
  tbb::enumerable_thread_specific<std::vector<uint64_t>> local(
      [pixels] { return std::vector<uint64_t>(pixels, kEmpty); });
  tbb::parallel_for(tbb::blocked_range<size_t>(0, surfels), [&](const tbb::blocked_range<size_t>& r) {
    std::vector<uint64_t>& buffer = local.local();
    const auto write = [&buffer](size_t pixel, uint64_t key) { buffer[pixel] = std::min(buffer[pixel], key); };
    for (size_t k = r.begin(); k < r.end(); ++k) splat(k, write);
  });
  std::vector<uint64_t> out(pixels, kEmpty);
  for (const std::vector<uint64_t>& buffer : local)
    for (size_t p = 0; p < pixels; ++p) out[p] = std::min(out[p], buffer[p]);
  return out;
}

void requireRange(bool ok, const std::string& setting, const std::string& rule) {
  if (!ok) throw InputError("fusion config: '" + setting + "' must be " + rule);
}

// One fused sample: camera-frame point and normal (facing the camera) at the fused resolution.
struct Measurement {
  Eigen::Vector3f point = Eigen::Vector3f::Zero();
  Eigen::Vector3f normal = Eigen::Vector3f::Zero();
  float weight = 0;  // 0 = not fused
  float radius = 0;
};

// A surfel seen from one camera. predict() keeps, per pixel, the surfel whose CENTRE is nearest
// (not the nearest intersection with a disc: with noisy normals neighbouring discs tilt towards
// the camera, and the nearest of several intersections lay 12 mm in front of the measured surface
// at the median on a noisy synthetic frame, against 8 mm for the nearest centre).
struct CameraView {
  Eigen::Matrix3f R_cam_world;
  Eigen::Vector3f t_cam_world;
  float fx, fy, cx, cy, min_depth;

  CameraView(const SE3& T_world_cam, const CameraIntrinsics& camera, double min_depth_m) {
    const SE3 T_cam_world = T_world_cam.inverse();
    R_cam_world = T_cam_world.linear().cast<float>();
    t_cam_world = T_cam_world.translation().cast<float>();
    fx = static_cast<float>(camera.fx);
    fy = static_cast<float>(camera.fy);
    cx = static_cast<float>(camera.cx);
    cy = static_cast<float>(camera.cy);
    min_depth = static_cast<float>(min_depth_m);
  }

  float centreDepth(const Surfel& s) const { return (R_cam_world * s.position + t_cam_world).z(); }

  Eigen::Vector3f centre(const Surfel& s) const { return R_cam_world * s.position + t_cam_world; }
  Eigen::Vector3f normal(const Surfel& s) const { return R_cam_world * s.normal; }
};

// A surfel's plane in a CameraView's frame (centre pc, normal nc) and its depth along the pixel
// rays ray(x, y) = ((x - cx) / fx, (y - cy) / fy, 1). nc . ray is a column term plus a row term
// plus nc.z, so a splat computes the terms once per column and row instead of per pixel (the same
// float operations: the same depths).
struct ViewPlane {
  const CameraView& view;
  Eigen::Vector3f nc;
  float n_dot_p, centre_z;

  ViewPlane(const CameraView& v, const Eigen::Vector3f& pc, const Eigen::Vector3f& n)
      : view(v), nc(n), n_dot_p(n.dot(pc)), centre_z(pc.z()) {}
  ViewPlane(const CameraView& v, const Surfel& s) : ViewPlane(v, v.centre(s), v.normal(s)) {}

  float columnTerm(int x) const { return nc.x() * (x - view.cx) / view.fx; }
  float rowTerm(int y) const { return nc.y() * (y - view.cy) / view.fy; }
  // Depth along the ray whose column and row terms sum to image_terms; the centre's depth where
  // the plane is seen nearly edge-on or the hit lands far from the centre.
  float depth(float image_terms) const {
    const float denom = image_terms + nc.z();
    const float z = std::abs(denom) > 1e-3f ? n_dot_p / denom : centre_z;
    return z >= view.min_depth && std::abs(z - centre_z) < 0.5f * centre_z ? z : centre_z;
  }
  float depth(int x, int y) const { return depth(columnTerm(x) + rowTerm(y)); }
};

constexpr float kMaxSquareHalf = 8;  // pixels: the largest max_half of squareSplat

// Calls visit(pixel, z) for every pixel of surfel s's splat as a square of half side `scale` times
// its projected radius (at least the pixel its centre falls in, at most 2 * max_half wide, max_half
// <= kMaxSquareHalf), z the depth of the surfel's plane there (ViewPlane). Nothing when the centre
// is nearer than min_depth.
template <class Visit>
void squareSplat(const Surfel& s, const CameraView& view, int w, int h, float max_half, float scale, Visit&& visit) {
  const Eigen::Vector3f pc = view.R_cam_world * s.position + view.t_cam_world;
  if (pc.z() < view.min_depth) return;
  const float inv_z = 1.0f / pc.z();
  const float u = view.fx * pc.x() * inv_z + view.cx, v = view.fy * pc.y() * inv_z + view.cy;
  const float half = std::clamp(scale * s.radius * std::max(view.fx, view.fy) * inv_z, 0.5f, max_half);
  const int x0 = std::max(0, static_cast<int>(std::ceil(u - half)));
  const int x1 = std::min(w - 1, static_cast<int>(std::floor(u + half)));
  const int y0 = std::max(0, static_cast<int>(std::ceil(v - half)));
  const int y1 = std::min(h - 1, static_cast<int>(std::floor(v + half)));
  const ViewPlane plane(view, pc, view.normal(s));
  std::array<float, 2 * static_cast<int>(kMaxSquareHalf) + 1> column_terms;
  for (int x = x0; x <= x1; ++x) column_terms[x - x0] = plane.columnTerm(x);
  for (int y = y0; y <= y1; ++y) {
    const float row_term = plane.rowTerm(y);
    for (int x = x0; x <= x1; ++x) visit(static_cast<size_t>(y) * w + x, plane.depth(column_terms[x - x0] + row_term));
  }
}

// Depth per pixel (0 = none): the confidence-weighted mean of the depths splat(k, visit) reports
// (visit(pixel, z)) within `band` * max(1, depth) of the front surfel's plane at that pixel, the
// front surfel being zbuffer's. The front surfel alone is the nearest of several noisy neighbours
// (one noisy synthetic 640x480 frame fused and predicted at its pose: median depth difference
// -8 mm for the front surfel, 0.0 mm for the mean; frame-to-model ATE on the static synthetic
// twin of seed 2: 31 mm before, 3.6 mm after).
// The sums are fixed-point integers (weights and weighted depths in units of 2^-24): integer
// addition does not depend on the order, so the result is the same bit for bit whatever the
// threads and their scheduling (per-thread float sums made runs differ in the last bits, and
// hard sequences then diverged).
template <class Splat>
std::vector<float> averagedDepth(const std::vector<Surfel>& surfels, const std::vector<uint64_t>& zbuffer,
                                 const CameraView& view, int w, float band, Splat&& splat) {
  const size_t pixels = zbuffer.size();
  std::vector<float> front(pixels, 0.0f);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, pixels), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t p = r.begin(); p < r.end(); ++p)
      if (zbuffer[p] != kEmpty)
        front[p] =
            ViewPlane(view, surfels[keyIndex(zbuffer[p])]).depth(static_cast<int>(p % w), static_cast<int>(p / w));
  });
  // Weight <= 10 and depth clamped to 1e4 m: a term is below 2^41, a pixel's sum of up to 2^20
  // terms fits an int64.
  constexpr double kScale = 1 << 24;
  constexpr float kMaxSummedDepth = 1e4f;
  using Sum = std::array<int64_t, 2>;  // sum of weights, sum of weight * depth
  tbb::enumerable_thread_specific<std::vector<Sum>> sums([pixels] { return std::vector<Sum>(pixels, Sum{0, 0}); });
  tbb::parallel_for(tbb::blocked_range<size_t>(0, surfels.size()), [&](const tbb::blocked_range<size_t>& r) {
    std::vector<Sum>& sum = sums.local();
    for (size_t k = r.begin(); k < r.end(); ++k) {
      const double weight = std::min(surfels[k].confidence, 10.0f);
      const int64_t weight_fixed = std::llround(weight * kScale);
      splat(k, [&](size_t pixel, float z) {
        if (std::abs(z - front[pixel]) < band * std::max(1.0f, front[pixel])) {
          sum[pixel][0] += weight_fixed;
          sum[pixel][1] += std::llround(weight * std::min(z, kMaxSummedDepth) * kScale);
        }
      });
    }
  });
  std::vector<Sum> total(pixels, Sum{0, 0});
  for (const auto& sum : sums)
    for (size_t p = 0; p < pixels; ++p) {
      total[p][0] += sum[p][0];
      total[p][1] += sum[p][1];
    }
  for (size_t p = 0; p < pixels; ++p)
    if (total[p][0] > 0) front[p] = static_cast<float>(static_cast<double>(total[p][1]) / total[p][0]);
  return front;
}

enum class Action : uint8_t { kNone, kMerge, kAdd, kDynamic };

// Throws InputError naming the frame when its images or the camera do not fit integrate().
void checkFusionInput(const RgbdFrame& frame, const CameraIntrinsics& camera, const cv::Mat& static_weight) {
  const std::string what = "fusion input '" + frame.name + "'";
  if (!camera.valid()) throw InputError(what + ": invalid camera intrinsics");
  if (frame.depth.empty() || frame.depth.type() != CV_32FC1) throw InputError(what + ": depth must be CV_32FC1");
  if (frame.depth.cols != camera.width || frame.depth.rows != camera.height)
    throw InputError(what + ": depth is " + std::to_string(frame.depth.cols) + "x" + std::to_string(frame.depth.rows) +
                     " but the camera is " + std::to_string(camera.width) + "x" + std::to_string(camera.height));
  if (frame.color.type() != CV_8UC3 || frame.color.size() != frame.depth.size())
    throw InputError(what + ": colour must be CV_8UC3 of the depth's size");
  if (frame.intensity.type() != CV_32FC1 || frame.intensity.size() != frame.depth.size())
    throw InputError(what + ": intensity must be CV_32FC1 of the depth's size");
  if (!static_weight.empty() && (static_weight.type() != CV_32FC1 || static_weight.size() != frame.depth.size()))
    throw InputError(what + ": static weight must be CV_32FC1 of the depth's size (or empty)");
}

// A frame's depth in [min_depth, max_depth] (metres; 0 outside) and its back-projection.
struct DepthPoints {
  const cv::Mat& depth;
  const CameraIntrinsics& camera;
  float min_depth, max_depth;

  float valid(int x, int y) const {
    const float z = depth.at<float>(y, x);
    return z >= min_depth && z <= max_depth ? z : 0.0f;
  }
  Eigen::Vector3f point(int x, int y, float z) const {
    return Eigen::Vector3f(static_cast<float>((x - camera.cx) / camera.fx) * z,
                           static_cast<float>((y - camera.cy) / camera.fy) * z, z);
  }
};

// The frame at the fused resolution (every stride-th input pixel), what one integrate() works on.
struct FusedGrid {
  int stride = 1, width = 0, height = 0;  // width x height fused pixels
  std::vector<Measurement> measurements;  // weight 0 = not fused
  // Every measured depth, whatever its weight, also beyond max_depth_m (the ray still crossed free
  // space): the free-space evidence. 0 = none.
  std::vector<float> depth;
  std::vector<float> dynamic_depth;  // depth of pixels weighted as dynamic, 0 = none

  size_t at(int i, int j) const { return static_cast<size_t>(j * width + i); }
  bool inside(int i, int j) const { return i >= 0 && j >= 0 && i < width && j < height; }
};

// The surface sample at input pixel (x, y) of valid depth z into m (weight and radius as given
// by the caller's footprint), or false (m untouched) where no normal can be estimated.
bool measureAt(const DepthPoints& d, int x, int y, float z, int stride, float discontinuity, float pixel_footprint,
               float weight, Measurement& m) {
  const Eigen::Vector3f p = d.point(x, y, z);
  // Central differences where the neighbour is on the same surface, one-sided otherwise.
  auto neighbour = [&](int nx, int ny, Eigen::Vector3f& out) {
    if (nx < 0 || ny < 0 || nx >= d.camera.width || ny >= d.camera.height) return false;
    const float nz = d.valid(nx, ny);
    if (nz == 0 || std::abs(nz - z) > discontinuity * z) return false;
    out = d.point(nx, ny, nz);
    return true;
  };
  auto difference = [&](int dx, int dy, Eigen::Vector3f& out) {
    Eigen::Vector3f a, b;
    const bool ha = neighbour(x + dx, y + dy, a), hb = neighbour(x - dx, y - dy, b);
    if (ha && hb) out = a - b;
    else if (ha) out = a - p;
    else if (hb) out = p - b;
    return ha || hb;
  };
  // Two fused pixels apart: over one, Kinect-like noise (5 mm at 2 m) tilts normals by ~20
  // degrees, associations fail and the map fills with duplicate surfels.
  Eigen::Vector3f du, dv;
  if (!difference(2 * stride, 0, du) || !difference(0, 2 * stride, dv)) return false;
  Eigen::Vector3f n = dv.cross(du);
  const float len = n.norm();
  if (len <= 0) return false;
  n /= len;
  const Eigen::Vector3f ray = p.normalized();
  float cos_view = -n.dot(ray);
  if (cos_view < 0) {
    n = -n;
    cos_view = -cos_view;
  }
  m.point = p;
  m.normal = n;
  m.weight = weight;
  m.radius = pixel_footprint * z / std::max(cos_view, 0.3f);
  return true;
}

// Phase 1 of integrate(): the measurements at the fused resolution and the depths behind them.
FusedGrid measureFrame(const RgbdFrame& frame, const CameraIntrinsics& camera, const cv::Mat& static_weight,
                       const FusionConfig& config) {
  FusedGrid g;
  g.stride = config.integration_stride;
  g.width = (camera.width + g.stride - 1) / g.stride;
  g.height = (camera.height + g.stride - 1) / g.stride;
  const size_t cells = static_cast<size_t>(g.width) * g.height;
  g.measurements.resize(cells);
  g.depth.assign(cells, 0.0f);
  g.dynamic_depth.assign(cells, 0.0f);
  const DepthPoints points{frame.depth, camera, static_cast<float>(config.min_depth_m),
                           static_cast<float>(config.max_depth_m)};
  const float discontinuity = static_cast<float>(config.depth_discontinuity_ratio);
  const float min_weight = static_cast<float>(config.min_static_weight);
  const float pixel_footprint = static_cast<float>(config.radius_scale * g.stride / std::min(camera.fx, camera.fy));
  tbb::parallel_for(tbb::blocked_range<int>(0, g.height), [&](const tbb::blocked_range<int>& rows) {
    for (int j = rows.begin(); j < rows.end(); ++j) {
      const int y = j * g.stride;
      for (int i = 0; i < g.width; ++i) {
        const int x = i * g.stride;
        const float raw = frame.depth.at<float>(y, x);
        g.depth[g.at(i, j)] = raw > 0 && std::isfinite(raw) ? raw : 0.0f;
        const float z = points.valid(x, y);
        if (z == 0) continue;
        const float w = static_weight.empty() ? 1.0f : static_weight.at<float>(y, x);
        if (!(w >= min_weight)) {
          g.dynamic_depth[g.at(i, j)] = z;
          continue;
        }
        measureAt(points, x, y, z, g.stride, discontinuity, pixel_footprint, std::min(w, 1.0f), g.measurements[g.at(i, j)]);
      }
    }
  });
  return g;
}

// Phase 2 of integrate(): the nearest surfel per fused pixel (kEmpty where none), and a free-space
// vote for every surfel in front of the measured surface (its 3x3 fused neighbourhood's nearest
// depth) by more than margin_m * max(1, depth).
std::vector<uint64_t> indexMap(std::vector<Surfel>& surfels, const FusedGrid& g, const CameraView& view,
                               float margin_m) {
  const float inv_stride = 1.0f / g.stride;
  return nearestSurfels(surfels.size(), g.measurements.size(), [&](size_t k, auto&& write) {
    Surfel& s = surfels[k];
    const Eigen::Vector3f pc = view.centre(s);
    if (pc.z() < view.min_depth) return;
    const int i = static_cast<int>(std::lround((view.fx * pc.x() / pc.z() + view.cx) * inv_stride));
    const int j = static_cast<int>(std::lround((view.fy * pc.y() / pc.z() + view.cy) * inv_stride));
    if (!g.inside(i, j)) return;
    write(g.at(i, j), depthKey(pc.z(), static_cast<uint32_t>(k)));
    float nearest = std::numeric_limits<float>::max();
    bool all_valid = i > 0 && j > 0 && i < g.width - 1 && j < g.height - 1;
    for (int dj = -1; dj <= 1 && all_valid; ++dj)
      for (int di = -1; di <= 1 && all_valid; ++di) {
        const float d = g.depth[g.at(i + di, j + dj)];
        all_valid = d > 0;
        nearest = std::min(nearest, d);
      }
    if (all_valid && pc.z() < nearest - margin_m * std::max(1.0f, nearest)) ++s.removal_votes;
  });
}

// Whether the disc of a surfel nearest at a fused pixel next to (i, j) already covers m's point.
bool coveredByNeighbour(const FusedGrid& g, const std::vector<uint64_t>& index_map, const std::vector<Surfel>& surfels,
                        const CameraView& view, int i, int j, const Measurement& m, float tolerance) {
  for (int dj = -1; dj <= 1; ++dj)
    for (int di = -1; di <= 1; ++di) {
      if (!g.inside(i + di, j + dj)) continue;
      const uint64_t key = index_map[g.at(i + di, j + dj)];
      if (key == kEmpty) continue;
      const Surfel& s = surfels[keyIndex(key)];
      const Eigen::Vector3f offset = m.point - view.centre(s);
      const float along = offset.dot(view.normal(s));
      if (std::abs(along) < tolerance && offset.squaredNorm() - along * along < s.radius * s.radius) return true;
    }
  return false;
}

// Phase 3 of integrate(), the decision per fused pixel (read-only): merge into the surfel nearest
// there, add a new one, vote the surfel there out as seen moving, or nothing.
std::vector<Action> decideActions(const FusedGrid& g, const std::vector<uint64_t>& index_map,
                                  const std::vector<Surfel>& surfels, const CameraView& view, const FusionConfig& config) {
  const float assoc = static_cast<float>(config.association_distance_m);
  const float cos_assoc = static_cast<float>(std::cos(config.association_angle_deg * M_PI / 180.0));
  const auto decide = [&](int i, int j) {
    const Measurement& m = g.measurements[g.at(i, j)];
    const uint64_t key = index_map[g.at(i, j)];
    if (const float zd = g.dynamic_depth[g.at(i, j)]; zd > 0 && config.dynamic_removal) {
      // A surfel where the frame now sees a moving surface: it was fused while that surface
      // stood still or before it was detected.
      const bool at_surfel = key != kEmpty && std::abs(keyDepth(key) - zd) < assoc * std::max(1.0f, zd);
      return at_surfel ? Action::kDynamic : Action::kNone;
    }
    if (m.weight == 0) return Action::kNone;
    const float tolerance = assoc * std::max(1.0f, m.point.z());
    if (key != kEmpty && std::abs(keyDepth(key) - m.point.z()) < tolerance &&
        view.normal(surfels[keyIndex(key)]).dot(m.normal) > cos_assoc)
      return Action::kMerge;
    // A surfel of a neighbouring pixel whose disc already covers this point: nothing to add.
    return coveredByNeighbour(g, index_map, surfels, view, i, j, m, tolerance) ? Action::kNone : Action::kAdd;
  };
  std::vector<Action> action(g.measurements.size(), Action::kNone);
  tbb::parallel_for(tbb::blocked_range<int>(0, g.height), [&](const tbb::blocked_range<int>& rows) {
    for (int j = rows.begin(); j < rows.end(); ++j)
      for (int i = 0; i < g.width; ++i) action[g.at(i, j)] = decide(i, j);
  });
  return action;
}

// The frame's colour and intensity at fused pixel (i, j).
cv::Vec3b bgrAt(const RgbdFrame& frame, const FusedGrid& g, int i, int j) {
  return frame.color.at<cv::Vec3b>(j * g.stride, i * g.stride);
}
float intensityAt(const RgbdFrame& frame, const FusedGrid& g, int i, int j) {
  return frame.intensity.at<float>(j * g.stride, i * g.stride);
}

// Applies phase 3's merges (confidence-weighted means, one association vote taken back) and
// dynamic votes. A pixel updates only the surfel nearest at it, so no two pixels write one surfel.
void mergeMeasurements(std::vector<Surfel>& surfels, const FusedGrid& g, const std::vector<uint64_t>& index_map,
                       const std::vector<Action>& action, const RgbdFrame& frame, const SE3& T_world_cam,
                       int frame_index) {
  const Eigen::Matrix3f R_world_cam = T_world_cam.linear().cast<float>();
  const Eigen::Vector3f t_world_cam = T_world_cam.translation().cast<float>();
  tbb::parallel_for(tbb::blocked_range<int>(0, g.height), [&](const tbb::blocked_range<int>& rows) {
    for (int j = rows.begin(); j < rows.end(); ++j)
      for (int i = 0; i < g.width; ++i) {
        const size_t cell = g.at(i, j);
        if (action[cell] == Action::kDynamic) ++surfels[keyIndex(index_map[cell])].removal_votes;
        if (action[cell] != Action::kMerge) continue;
        const Measurement& m = g.measurements[cell];
        Surfel& s = surfels[keyIndex(index_map[cell])];
        const float c = s.confidence, w = m.weight, sum = c + w;
        s.position = (c * s.position + w * (R_world_cam * m.point + t_world_cam)) / sum;
        s.normal = (c * s.normal + w * (R_world_cam * m.normal)).normalized();
        s.radius = (c * s.radius + w * m.radius) / sum;
        const cv::Vec3b bgr = bgrAt(frame, g, i, j);
        for (int ch = 0; ch < 3; ++ch) s.bgr[ch] = (c * s.bgr[ch] + w * bgr[ch]) / sum;
        s.intensity = (c * s.intensity + w * intensityAt(frame, g, i, j)) / sum;
        s.confidence = sum;
        s.last_seen = frame_index;
        s.removal_votes = std::max(0, s.removal_votes - 1);
      }
  });
}

// Phase 5 of integrate(): a new surfel per pixel phase 3 chose to add, in row order, while the map
// holds fewer than `budget`. Returns false when the budget stopped it.
bool addSurfels(std::vector<Surfel>& surfels, size_t budget, const FusedGrid& g, const std::vector<Action>& action,
                const RgbdFrame& frame, const SE3& T_world_cam, int frame_index) {
  const Eigen::Matrix3f R_world_cam = T_world_cam.linear().cast<float>();
  const Eigen::Vector3f t_world_cam = T_world_cam.translation().cast<float>();
  for (int j = 0; j < g.height; ++j)
    for (int i = 0; i < g.width; ++i) {
      if (action[g.at(i, j)] != Action::kAdd) continue;
      if (surfels.size() >= budget) return false;
      const Measurement& m = g.measurements[g.at(i, j)];
      Surfel s;
      s.position = R_world_cam * m.point + t_world_cam;
      s.normal = R_world_cam * m.normal;
      s.radius = m.radius;
      s.confidence = m.weight;
      const cv::Vec3b bgr = bgrAt(frame, g, i, j);
      for (int ch = 0; ch < 3; ++ch) s.bgr[ch] = bgr[ch];
      s.intensity = intensityAt(frame, g, i, j);
      s.created = s.last_seen = frame_index;
      surfels.push_back(s);
    }
  return true;
}

// Unstable surfels are drawn for tracking only while they are being observed (noise and the
// unmasked parts of moving objects stay out of the tracking reference, as in ElasticFusion).
bool drawnForTracking(const Surfel& s, float stable_confidence, int latest_frame) {
  return s.confidence >= stable_confidence || s.last_seen >= latest_frame;
}

// Calls visit(pixel, z) for every pixel of a w x h image whose ray meets surfel s's disc, z the
// hit's depth; nothing for a surfel nearer than min_depth or seen from behind. Discs larger than
// max_half_px (radius, pixels) are clipped: only views much closer than any fused one produce
// them, and the cost grows with the square.
template <class Visit>
void discSplat(const Surfel& s, const CameraView& view, int w, int h, float max_half_px, Visit&& visit) {
  const auto& [R_cam_world, t_cam_world, fx, fy, cx, cy, min_depth] = view;
  const Eigen::Vector3f pc = R_cam_world * s.position + t_cam_world;
  if (pc.z() < min_depth) return;
  const Eigen::Vector3f nc = R_cam_world * s.normal;
  const float n_dot_p = nc.dot(pc);
  if (n_dot_p >= 0) return;  // seen from behind
  const float u = fx * pc.x() / pc.z() + cx, v = fy * pc.y() / pc.z() + cy;
  // Bounding box of the disc's image: an ellipse with semi-axes radius_px and radius_px * cos(view
  // angle), the short one along the image direction in which the normal tilts away. Oblique
  // discs (floors, walls seen at grazing angles) are the large ones, so this halves the work.
  // The 15 % margin covers perspective; the exact ray-disc test below decides.
  const float radius_px = std::min(max_half_px, s.radius * std::max(fx, fy) / pc.z());
  const float cos_view = -n_dot_p / pc.norm();
  Eigen::Vector2f tilt(nc.x() * pc.z() - nc.z() * pc.x(), nc.y() * pc.z() - nc.z() * pc.y());
  const float tilt_norm = tilt.norm();
  tilt = tilt_norm > 1e-9f ? Eigen::Vector2f(tilt / tilt_norm) : Eigen::Vector2f(1, 0);
  const float c2 = cos_view * cos_view;
  const float half_u = 1.15f * radius_px * std::sqrt(tilt.y() * tilt.y() + c2 * tilt.x() * tilt.x());
  const float half_v = 1.15f * radius_px * std::sqrt(tilt.x() * tilt.x() + c2 * tilt.y() * tilt.y());
  const int x0 = std::max(0, static_cast<int>(std::ceil(u - half_u)));
  const int x1 = std::min(w - 1, static_cast<int>(std::floor(u + half_u)));
  const int y0 = std::max(0, static_cast<int>(std::ceil(v - half_v)));
  const int y1 = std::min(h - 1, static_cast<int>(std::floor(v + half_v)));
  const float r2 = s.radius * s.radius;
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      // Where the pixel's ray meets the surfel's plane, if inside its disc.
      const Eigen::Vector3f ray((x - cx) / fx, (y - cy) / fy, 1.0f);
      const float denom = nc.dot(ray);
      if (denom > -1e-4f) continue;
      const float z = n_dot_p / denom;
      if (z < min_depth || (z * ray - pc).squaredNorm() > r2) continue;
      visit(static_cast<size_t>(y) * w + x, z);
    }
}

// predict()'s images from its z-buffer (front surfel per pixel) and averaged depth.
ModelPrediction predictionImages(const std::vector<Surfel>& surfels, const std::vector<uint64_t>& zbuffer,
                                 const std::vector<float>& depth, const CameraView& view, int w, int h) {
  ModelPrediction out;
  out.depth = cv::Mat::zeros(h, w, CV_32FC1);
  out.intensity = cv::Mat::zeros(h, w, CV_32FC1);
  out.color = cv::Mat::zeros(h, w, CV_8UC3);
  out.normal = cv::Mat::zeros(h, w, CV_32FC3);
  tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y < rows.end(); ++y)
      for (int x = 0; x < w; ++x) {
        const uint64_t key = zbuffer[static_cast<size_t>(y) * w + x];
        if (key == kEmpty) continue;
        const Surfel& s = surfels[keyIndex(key)];
        out.depth.at<float>(y, x) = depth[static_cast<size_t>(y) * w + x];
        out.intensity.at<float>(y, x) = s.intensity;
        out.color.at<cv::Vec3b>(y, x) = cv::Vec3b(cv::saturate_cast<uchar>(s.bgr[0]),
                                                  cv::saturate_cast<uchar>(s.bgr[1]),
                                                  cv::saturate_cast<uchar>(s.bgr[2]));
        const Eigen::Vector3f nc = view.normal(s);
        out.normal.at<cv::Vec3f>(y, x) = cv::Vec3f(nc.x(), nc.y(), nc.z());
      }
  });
  return out;
}

}  // namespace

void validate(const FusionConfig& c) {
  requireRange(c.integration_stride >= 1 && c.integration_stride <= 8, "integration_stride", "in 1..8");
  requireRange(c.min_depth_m > 0 && c.max_depth_m > c.min_depth_m, "min_depth_m/max_depth_m",
               "positive with min_depth_m < max_depth_m");
  requireRange(c.min_static_weight > 0 && c.min_static_weight <= 1, "min_static_weight", "in (0, 1]");
  requireRange(c.association_distance_m > 0, "association_distance_m", "positive");
  requireRange(c.association_angle_deg > 0 && c.association_angle_deg <= 90, "association_angle_deg", "in (0, 90]");
  requireRange(c.depth_discontinuity_ratio > 0, "depth_discontinuity_ratio", "positive");
  requireRange(c.radius_scale > 0, "radius_scale", "positive");
  requireRange(c.stable_confidence > 0, "stable_confidence", "positive");
  requireRange(c.unstable_window_frames >= 1, "unstable_window_frames", "at least 1");
  requireRange(c.free_space_margin_m > 0, "free_space_margin_m", "positive");
  requireRange(c.free_space_votes >= 1, "free_space_votes", "at least 1");
  requireRange(c.max_surfels >= 1, "max_surfels", "at least 1");
  requireRange(c.keyframe_distance_m > 0 && c.keyframe_angle_deg > 0, "keyframe_distance_m/keyframe_angle_deg",
               "positive");
  requireRange(c.max_keyframes >= 2, "max_keyframes", "at least 2");
  requireRange(c.mesh_voxel_m > 0 && c.mesh_truncation_m > c.mesh_voxel_m, "mesh_voxel_m/mesh_truncation_m",
               "positive with mesh_truncation_m > mesh_voxel_m");
}

StaticMap::StaticMap(const FusionConfig& config) : config_(config) {
  validate(config_);
  // The whole budget's address space at once: pages are touched only as surfels are added, and
  // the storage never grows by copying (a doubling held both copies at its peak).
  surfels_.reserve(static_cast<size_t>(config_.max_surfels));
}

void StaticMap::integrate(const RgbdFrame& frame, const CameraIntrinsics& camera, const SE3& T_world_cam,
                          const cv::Mat& static_weight) {
  checkFusionInput(frame, camera, static_weight);
  const CameraView view(T_world_cam, camera, config_.min_depth_m);
  // 1. Measurements at the fused resolution, 2. the surfel nearest at each and free-space votes,
  // 3. per fused pixel: merge, add or a dynamic vote (decided read-only, then applied).
  const FusedGrid grid = measureFrame(frame, camera, static_weight, config_);
  const std::vector<uint64_t> index_map =
      indexMap(surfels_, grid, view, static_cast<float>(config_.free_space_margin_m));
  const std::vector<Action> action = decideActions(grid, index_map, surfels_, view, config_);
  mergeMeasurements(surfels_, grid, index_map, action, frame, T_world_cam, frame_index_);

  // 4. Remove surfels seen through or seen moving, and those that never became stable.
  const float stable = static_cast<float>(config_.stable_confidence);
  const int window = config_.unstable_window_frames;
  const int votes = config_.free_space_votes;
  const int frame_index = frame_index_;
  std::erase_if(surfels_, [&](const Surfel& s) {
    return s.removal_votes >= votes || (s.confidence < stable && frame_index - s.created > window);
  });

  // 5. New surfels, within the memory budget.
  if (!addSurfels(surfels_, static_cast<size_t>(config_.max_surfels), grid, action, frame, T_world_cam, frame_index_)) {
    if (!budget_reached_)
      spdlog::warn("fusion: the map reached its budget of {} surfels (setting max_surfels); new surfaces "
                   "are no longer added",
                   config_.max_surfels);
    budget_reached_ = true;
  }

  updateKeyframes(T_world_cam, camera);
  ++frame_index_;
}

void StaticMap::updateKeyframes(const SE3& T_world_cam, const CameraIntrinsics& camera) {
  keyframe_camera_ = camera;
  if (!keyframes_.empty()) {
    const SE3 T_last_cam = keyframes_.back().inverse() * T_world_cam;
    if (translationNorm(T_last_cam) < config_.keyframe_distance_m &&
        rotationAngleDeg(T_last_cam) < config_.keyframe_angle_deg)
      return;
  }
  keyframes_.push_back(T_world_cam);
  if (static_cast<int>(keyframes_.size()) > config_.max_keyframes) {
    // Keep every second one so the kept poses stay spread over the whole sequence.
    std::vector<SE3> thinned;
    for (size_t k = 0; k < keyframes_.size(); k += 2) thinned.push_back(keyframes_[k]);
    keyframes_ = std::move(thinned);
  }
}

ModelPrediction StaticMap::predict(const SE3& T_world_cam, const CameraIntrinsics& camera) const {
  if (!camera.valid()) throw InputError("fusion predict: invalid camera intrinsics");
  const int w = camera.width, h = camera.height;
  const CameraView view(T_world_cam, camera, config_.min_depth_m);
  constexpr float kMaxHalfSplat = 8;  // pixels: discSplat's clipping
  const float stable = static_cast<float>(config_.stable_confidence);
  const int latest = frame_index_ - 1;
  const auto splat = [&](size_t k, auto&& visit) {
    if (drawnForTracking(surfels_[k], stable, latest)) discSplat(surfels_[k], view, w, h, kMaxHalfSplat, visit);
  };
  const std::vector<uint64_t> zbuffer =
      nearestSurfels(surfels_.size(), static_cast<size_t>(w) * h, [&](size_t k, auto&& write) {
        const uint64_t centre_key = depthKey(view.centreDepth(surfels_[k]), static_cast<uint32_t>(k));
        splat(k, [&](size_t pixel, float) { write(pixel, centre_key); });
      });
  const std::vector<float> depth =
      averagedDepth(surfels_, zbuffer, view, w, static_cast<float>(config_.association_distance_m), splat);
  return predictionImages(surfels_, zbuffer, depth, view, w, h);
}

cv::Mat StaticMap::predictDepth(const SE3& T_world_cam, const CameraIntrinsics& camera) const {
  if (!camera.valid()) throw InputError("fusion predict: invalid camera intrinsics");
  const int w = camera.width, h = camera.height;
  const CameraView view(T_world_cam, camera, config_.min_depth_m);
  const float stable = static_cast<float>(config_.stable_confidence);
  const int latest = frame_index_ - 1;
  constexpr float kMaxHalfSplat = 8;  // pixels; see predict()
  // Half side of the square over the projected radius: 0.5 keeps it inside the disc's image up to
  // ~45 deg oblique, where the plane's depth needs no ray-disc test; the most accurate and among the
  // fastest of the sizes measured (docs/tuning.md#predict_depth).
  constexpr float kInnerSquare = 0.5f;
  // predict()'s surfels (the same rule for unstable ones, none seen from behind).
  const auto splat = [&](size_t k, auto&& visit) {
    const Surfel& s = surfels_[k];
    if (s.confidence < stable && s.last_seen < latest) return;
    if ((view.R_cam_world * s.normal).dot(view.R_cam_world * s.position + view.t_cam_world) >= 0) return;
    squareSplat(s, view, w, h, kMaxHalfSplat, kInnerSquare, visit);
  };
  const size_t pixels = static_cast<size_t>(w) * h;
  const std::vector<uint64_t> zbuffer = nearestSurfels(surfels_.size(), pixels, [&](size_t k, auto&& write) {
    const uint64_t centre_key = depthKey(view.centreDepth(surfels_[k]), static_cast<uint32_t>(k));
    splat(k, [&](size_t pixel, float) { write(pixel, centre_key); });
  });
  const std::vector<float> depth =
      averagedDepth(surfels_, zbuffer, view, w, static_cast<float>(config_.association_distance_m), splat);
  return cv::Mat(h, w, CV_32FC1, const_cast<float*>(depth.data())).clone();
}

cv::Mat StaticMap::predictStableDepth(const SE3& T_world_cam, const CameraIntrinsics& camera, cv::Mat* intensity) const {
  if (!camera.valid()) throw InputError("fusion predict: invalid camera intrinsics");
  const int w = camera.width, h = camera.height;
  const CameraView view(T_world_cam, camera, config_.min_depth_m);
  const float stable = static_cast<float>(config_.stable_confidence);
  constexpr float kMaxHalfSplat = 4;  // pixels; see predict()
  const size_t pixels = static_cast<size_t>(w) * h;

  const std::vector<uint64_t> zbuffer = nearestSurfels(surfels_.size(), pixels, [&](size_t k, auto&& write) {
    if (surfels_[k].confidence < stable) return;
    squareSplat(surfels_[k], view, w, h, kMaxHalfSplat, 1.0f,
                [&](size_t pixel, float z) { write(pixel, depthKey(z, static_cast<uint32_t>(k))); });
  });
  cv::Mat depth(h, w, CV_32FC1);
  if (intensity) intensity->create(h, w, CV_32FC1);
  for (int y = 0; y < h; ++y) {
    float* row = depth.ptr<float>(y);
    float* grey = intensity ? intensity->ptr<float>(y) : nullptr;
    for (int x = 0; x < w; ++x) {
      const uint64_t key = zbuffer[static_cast<size_t>(y) * w + x];
      row[x] = key == kEmpty ? 0.0f : keyDepth(key);
      if (grey) grey[x] = key == kEmpty ? 0.0f : surfels_[keyIndex(key)].intensity;
    }
  }
  return depth;
}

bool StaticMap::hasStableSurfels() const {
  return std::any_of(surfels_.begin(), surfels_.end(),
                     [&](const Surfel& s) { return s.confidence >= config_.stable_confidence; });
}

MapPoints StaticMap::points() const {
  MapPoints out;
  for (const Surfel& s : surfels_) {
    if (s.confidence < config_.stable_confidence) continue;
    out.positions.push_back(s.position);
    out.normals.push_back(s.normal);
    out.colors.emplace_back(cv::saturate_cast<uchar>(s.bgr[0]), cv::saturate_cast<uchar>(s.bgr[1]),
                            cv::saturate_cast<uchar>(s.bgr[2]));
  }
  return out;
}

}  // namespace ff
