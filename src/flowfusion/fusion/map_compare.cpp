#include "flowfusion/fusion/map_compare.h"

#include <open3d/geometry/PointCloud.h>
#include <open3d/io/PointCloudIO.h>
#include <open3d/utility/Logging.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "flowfusion/core/error.h"

namespace ff {

namespace {

open3d::geometry::PointCloud toCloud(const std::vector<Eigen::Vector3f>& points) {
  open3d::geometry::PointCloud cloud;
  cloud.points_.reserve(points.size());
  for (const auto& p : points) cloud.points_.push_back(p.cast<double>());
  return cloud;
}

// Bytes of one value of a PLY property type (0 for an unknown type).
size_t plyTypeBytes(const std::string& type) {
  if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
  if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
  if (type == "int" || type == "uint" || type == "float" || type == "int32" || type == "uint32" ||
      type == "float32")
    return 4;
  if (type == "double" || type == "float64") return 8;
  return 0;
}

// A PLY file's header must not promise more elements than its body can hold: Open3D allocates
// what the header declares before reading (2e9 vertices: std::bad_alloc). Each element needs at
// least its fixed-size properties' bytes (binary) or two characters per property (ASCII).
void checkPlyHeader(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  if (!std::getline(in, line) || (line != "ply" && line != "ply\r")) return;  // not PLY: Open3D decides
  bool ascii = false;
  long double needed = 0, count = 0, per_element = 0;
  for (int lines = 0; std::getline(in, line) && lines < 10000; ++lines) {
    std::istringstream words(line);
    std::string word, type;
    words >> word;
    if (word == "format") {
      words >> type;
      ascii = type == "ascii";
    } else if (word == "element") {
      needed += count * per_element;
      count = 0;
      per_element = 0;
      words >> type >> count;
    } else if (word == "property") {
      words >> type;
      per_element += ascii ? 2 : (type == "list" ? 1 : plyTypeBytes(type));
    } else if (word == "end_header") {
      needed += count * per_element;
      std::error_code ec;
      const auto size = std::filesystem::file_size(path, ec);
      const auto body = static_cast<long double>(ec ? 0 : size) - static_cast<long double>(in.tellg());
      if (needed > body)
        throw InputError(path + ": PLY header declares more elements than the file holds (" +
                         std::to_string(static_cast<long long>(body)) +
                         " bytes after the header; corrupt or cut short?)");
      return;
    }
  }
}

}  // namespace

MapDifference mapDifference(const std::vector<Eigen::Vector3f>& from, const std::vector<Eigen::Vector3f>& to,
                            double threshold_m) {
  if (!(threshold_m > 0) || !std::isfinite(threshold_m))
    throw InputError("map comparison threshold must be a positive number of metres, got " +
                     std::to_string(threshold_m));
  MapDifference d;
  d.points = from.size();
  if (from.empty()) return d;
  if (to.empty())
    throw InputError("cannot compare a map of " + std::to_string(from.size()) + " points with an empty map");

  // An exact k-d tree (Open3D, nanoflann) is fast enough: `eval map` on two 300k-point clouds,
  // both directions and both files read, takes 0.6 s on one core.
  std::vector<double> distances = toCloud(from).ComputePointCloudDistance(toCloud(to));
  double sum = 0;
  size_t beyond = 0;
  for (double v : distances) {
    sum += v;
    beyond += v > threshold_m;
  }
  const double n = static_cast<double>(distances.size());
  d.mean_m = sum / n;
  d.fraction_beyond = static_cast<double>(beyond) / n;
  const auto mid = distances.begin() + static_cast<std::ptrdiff_t>(distances.size() / 2);
  std::nth_element(distances.begin(), mid, distances.end());
  d.median_m = distances.size() % 2 == 1 ? *mid : 0.5 * (*std::max_element(distances.begin(), mid) + *mid);
  return d;
}

MapComparison compareMaps(const std::vector<Eigen::Vector3f>& reference, const std::vector<Eigen::Vector3f>& test,
                          double threshold_m) {
  return {threshold_m, mapDifference(test, reference, threshold_m), mapDifference(reference, test, threshold_m)};
}

std::vector<Eigen::Vector3f> readMapPoints(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path + ": point cloud file does not exist");
  if (!fs::is_regular_file(path, ec)) throw InputError(path + ": not a point cloud file");

  checkPlyHeader(path);
  open3d::geometry::PointCloud cloud;
  {
    // Open3D warns on stdout about files it cannot parse; the InputError below says it instead.
    open3d::utility::VerbosityContextManager quiet(open3d::utility::VerbosityLevel::Error);
    quiet.Enter();
    const bool ok = open3d::io::ReadPointCloud(path, cloud);
    quiet.Exit();
    if (!ok) throw InputError(path + ": unreadable point cloud (corrupt, or not a PLY/PCD/XYZ file)");
  }
  if (cloud.points_.empty()) throw InputError(path + ": point cloud holds no points");

  std::vector<Eigen::Vector3f> points;
  points.reserve(cloud.points_.size());
  for (const auto& p : cloud.points_) {
    if (!p.allFinite()) throw InputError(path + ": point cloud holds non-finite coordinates");
    points.push_back(p.cast<float>());
  }
  return points;
}

TruthCloud::TruthCloud(double voxel_m) : voxel_m_(voxel_m) {
  if (!(voxel_m > 0) || !std::isfinite(voxel_m)) throw InputError("truth cloud: the voxel size must be > 0 m");
}

void TruthCloud::addDepth(const cv::Mat& depth_m, const CameraIntrinsics& camera, const SE3& T_world_cam,
                          int pixel_step) {
  if (depth_m.type() != CV_32FC1) throw InputError("truth cloud: depth must be CV_32FC1 metres");
  const int step = std::max(1, pixel_step);
  for (int v = 0; v < depth_m.rows; v += step) {
    const float* row = depth_m.ptr<float>(v);
    for (int u = 0; u < depth_m.cols; u += step) {
      if (!(row[u] > 0)) continue;
      const Eigen::Vector3d p = T_world_cam * camera.backproject(u, v, row[u]);
      // 21 bits per axis: +-10 km at 1 cm, far beyond a room.
      uint64_t key = 0;
      for (int c = 0; c < 3; ++c)
        key = key << 21 | (static_cast<uint64_t>(static_cast<int64_t>(std::floor(p(c) / voxel_m_)) + (1 << 20)) &
                           ((1u << 21) - 1));
      if (voxels_.insert(key).second) points_.push_back(p.cast<float>());
    }
  }
}

}  // namespace ff
