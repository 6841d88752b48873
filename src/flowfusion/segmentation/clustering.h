#pragma once
// Over-segmentation of frame A's point cloud into clusters with an adjacency graph
// (the paper's first step; docs/design.md).
#include <Eigen/Core>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <string>
#include <utility>
#include <vector>

#include "flowfusion/core/camera.h"
#include "flowfusion/core/config_enum.h"
#include "flowfusion/core/rgbd_frame.h"

namespace ff {

struct ClusterGraph {
  cv::Mat labels;  // CV_32S per pixel of A: cluster 0..num_clusters-1, -1 = no cluster (no depth)
  int num_clusters = 0;
  std::vector<std::pair<int, int>> edges;  // adjacent clusters, i < j, unique, sorted
  std::vector<int> sizes;                  // pixels per cluster
  std::vector<float> mean_depth;           // metres
  std::vector<Eigen::Vector3f> centroids;  // camera frame of A, metres
};

enum class ClusteringBackend { KMeans, Supervoxel };
FLOWFUSION_CONFIG_ENUM(ClusteringBackend, "clustering.backend", {ClusteringBackend::KMeans, "kmeans"},
                       {ClusteringBackend::Supervoxel, "supervoxel"})

struct ClusteringConfig {
  // kmeans: k-means on back-projected 3D points of a subsampled image, labels propagated to full
  // resolution (fast, and clusters stay inside objects); supervoxel: pcl::SupervoxelClustering,
  // the paper's choice, several times slower (docs/tuning.md#clustering).
  ClusteringBackend backend = ClusteringBackend::KMeans;

  // kmeans: number of clusters, seeded on a regular image grid; enough that no cluster leaks from
  // an object onto the wall behind it (docs/tuning.md#clustering).
  int kmeans_clusters = 192;
  // kmeans: the points clustered are every `kmeans_subsample`-th pixel in x and y.
  int kmeans_subsample = 8;
  // kmeans: Lloyd iterations.
  int kmeans_iterations = 10;

  // supervoxel: octree voxel size and seed spacing, metres. With the single-camera transform
  // (on) voxels grow with depth as the Kinect's depth noise does.
  double voxel_resolution = 0.02;
  double seed_resolution = 0.15;
  // supervoxel: weights of intensity (as grey "colour"), spatial and normal distances.
  double color_importance = 0.2;
  double spatial_importance = 0.4;
  double normal_importance = 1.0;

  // Both: two touching clusters are adjacent only where their depths along the shared image
  // boundary differ by less than this fraction of the depth (a depth jump separates objects).
  double adjacency_max_rel_depth_jump = 0.05;
  // Both: at least this many boundary pixel pairs must pass the depth test for an edge.
  int adjacency_min_contacts = 3;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(ClusteringConfig, backend, kmeans_clusters, kmeans_subsample,
                                                kmeans_iterations, voxel_resolution, seed_resolution,
                                                color_importance, spatial_importance, normal_importance,
                                                adjacency_max_rel_depth_jump, adjacency_min_contacts)

class Clusterer {
 public:
  virtual ~Clusterer() = default;
  // Every pixel with a valid depth (> 0, finite) gets a cluster. Throws InputError when the
  // frame's depth is not CV_32FC1 or its size differs from the camera's.
  virtual ClusterGraph cluster(const RgbdFrame& frame, const CameraIntrinsics& camera) = 0;
  virtual std::string name() const = 0;
};

// Throws InputError naming the first bad setting.
void validate(const ClusteringConfig& config);

// The backend the configuration names; throws InputError on a bad configuration.
std::unique_ptr<Clusterer> makeClusterer(const ClusteringConfig& config);

}  // namespace ff
