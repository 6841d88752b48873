#pragma once
// How far two map point clouds (map_points.ply of two runs) lie from each other: for every point of
// one map, the distance to the nearest point of the other. Made for checks such as "the dynamic
// run's map differs from the static run's map by at most 2% of its points (farther than 3 cm)".
// Both directions are reported because they answer different questions: TEST against REFERENCE
// counts what TEST added (ghosts, drift), REFERENCE against TEST what TEST lost (holes).
#include <nlohmann/json.hpp>

#include <Eigen/Core>
#include <cstddef>
#include <opencv2/core.hpp>
#include <string>
#include <unordered_set>
#include <vector>

#include "flowfusion/core/camera.h"
#include "flowfusion/core/se3.h"

namespace ff {

// Nearest-neighbour distances from the points of one cloud to another cloud.
struct MapDifference {
  size_t points = 0;             // points of the cloud measured
  double mean_m = 0;             // mean nearest distance, metres
  double median_m = 0;           // median nearest distance, metres
  double fraction_beyond = 0;    // fraction of the points whose nearest distance exceeds the threshold
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(MapDifference, points, mean_m, median_m, fraction_beyond)

struct MapComparison {
  double threshold_m = 0;
  MapDifference test_to_reference;  // every TEST point against REFERENCE
  MapDifference reference_to_test;  // every REFERENCE point against TEST
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(MapComparison, threshold_m, test_to_reference, reference_to_test)

// Distances from every point of `from` to its nearest point of `to` (exact, k-d tree). An empty
// `from` gives all zeros. Throws InputError when `to` is empty while `from` is not (no distance
// exists) or when threshold_m is not a positive number.
MapDifference mapDifference(const std::vector<Eigen::Vector3f>& from, const std::vector<Eigen::Vector3f>& to,
                            double threshold_m);

// Both directions; same errors as mapDifference.
MapComparison compareMaps(const std::vector<Eigen::Vector3f>& reference, const std::vector<Eigen::Vector3f>& test,
                          double threshold_m);

// A truth point cloud from depth images at known poses (a synthetic sequence's exact depth at its
// ground-truth poses: the room's surfaces), thinned to the first point in each voxel_m cube so a
// surface seen in many frames counts once. The map's share farther than a few centimetres from it
// is what drift left doubled (a wall fused twice, a few centimetres apart) or ghosts.
class TruthCloud {
 public:
  // Throws InputError when voxel_m is not a positive number.
  explicit TruthCloud(double voxel_m);
  // Every pixel_step-th pixel of `depth_m` (CV_32F, metres, 0 = none) in the world frame.
  void addDepth(const cv::Mat& depth_m, const CameraIntrinsics& camera, const SE3& T_world_cam, int pixel_step);
  const std::vector<Eigen::Vector3f>& points() const { return points_; }

 private:
  double voxel_m_;
  std::unordered_set<uint64_t> voxels_;
  std::vector<Eigen::Vector3f> points_;
};

// The points of a point cloud file (PLY as written by StaticMap::exportPointCloud; other formats
// Open3D reads by extension work too). Throws InputError naming the file when it is missing,
// unreadable, holds no points or holds non-finite coordinates.
std::vector<Eigen::Vector3f> readMapPoints(const std::string& path);

}  // namespace ff
