#include <algorithm>
#include <cmath>
#include <cstdio>
#include <deque>
#include <stdexcept>

#include "flowfusion/core/error.h"
#include "flowfusion/segmentation/cluster_graph_builder.h"

namespace ff {

std::unique_ptr<Clusterer> makeKMeansClusterer(const ClusteringConfig& config);
std::unique_ptr<Clusterer> makeSupervoxelClusterer(const ClusteringConfig& config);

void validate(const ClusteringConfig& config) {
  if (!(config.adjacency_max_rel_depth_jump > 0))
    throw InputError("clustering.adjacency_max_rel_depth_jump must be > 0");
  if (config.adjacency_min_contacts < 1) throw InputError("clustering.adjacency_min_contacts must be >= 1");
  if (config.kmeans_clusters < 1 || config.kmeans_clusters > 100000)
    throw InputError("clustering.kmeans_clusters must be 1 to 100000");
  if (config.kmeans_subsample < 1 || config.kmeans_subsample > 64)
    throw InputError("clustering.kmeans_subsample must be 1 to 64");
  if (config.kmeans_iterations < 1 || config.kmeans_iterations > 1000)
    throw InputError("clustering.kmeans_iterations must be 1 to 1000");
  // PCL asserts (and aborts the program) when its octree needs more levels than its keys hold,
  // and takes minutes and gigabytes well before that: voxels below a millimetre are refused here.
  const auto require = [](bool ok, const std::string& message) {
    if (!ok) throw InputError("clustering." + message);
  };
  const auto num = [](double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", v);
    return std::string(buf);
  };
  require(config.voxel_resolution >= 0.001 && config.voxel_resolution <= 1.0,
          "voxel_resolution must be 0.001 to 1 metre, got " + num(config.voxel_resolution));
  require(config.seed_resolution > config.voxel_resolution && config.seed_resolution <= 10.0,
          "seed_resolution must be above voxel_resolution and at most 10 metres, got " +
              num(config.seed_resolution));
  for (const auto& [name, value] : {std::pair{"color_importance", config.color_importance},
                                    std::pair{"spatial_importance", config.spatial_importance},
                                    std::pair{"normal_importance", config.normal_importance}})
    require(value >= 0 && value <= 1e3, std::string(name) + " must be 0 to 1000, got " + num(value));
}

std::unique_ptr<Clusterer> makeClusterer(const ClusteringConfig& config) {
  validate(config);
  switch (config.backend) {
    case ClusteringBackend::KMeans:
      return makeKMeansClusterer(config);
    case ClusteringBackend::Supervoxel:
      return makeSupervoxelClusterer(config);
  }
  throw std::logic_error("makeClusterer: unhandled clustering.backend");
}

namespace detail {

namespace {

bool continuous(float za, float zb, double max_rel) {
  return std::abs(za - zb) < max_rel * std::min(za, zb);
}

}  // namespace

void checkClusterInput(const RgbdFrame& frame, const CameraIntrinsics& camera, const std::string& who) {
  if (frame.depth.empty() || frame.depth.type() != CV_32FC1)
    throw InputError(who + ": frame '" + frame.name + "' has no CV_32FC1 depth image");
  if (frame.depth.cols != camera.width || frame.depth.rows != camera.height)
    throw InputError(who + ": frame '" + frame.name + "' is " + std::to_string(frame.depth.cols) + "x" +
                     std::to_string(frame.depth.rows) + " but the camera is " + std::to_string(camera.width) + "x" +
                     std::to_string(camera.height));
}

void fillUnlabeled(cv::Mat& labels, const cv::Mat& depth, double max_rel, int& num_clusters) {
  const int W = labels.cols, H = labels.rows;
  bool any_missing = false;
  for (int v = 0; v < H && !any_missing; ++v) {
    const int* l = labels.ptr<int>(v);
    const float* z = depth.ptr<float>(v);
    for (int u = 0; u < W; ++u) any_missing |= l[u] < 0 && validDepth(z[u]);
  }
  if (!any_missing) return;
  std::deque<int> queue;
  for (int v = 0; v < H; ++v)
    for (int u = 0; u < W; ++u)
      if (labels.at<int>(v, u) >= 0) {
        const bool border = (u > 0 && labels.at<int>(v, u - 1) < 0) || (u + 1 < W && labels.at<int>(v, u + 1) < 0) ||
                            (v > 0 && labels.at<int>(v - 1, u) < 0) || (v + 1 < H && labels.at<int>(v + 1, u) < 0);
        if (border) queue.push_back(v * W + u);
      }
  auto grow = [&](std::deque<int>& q) {
    while (!q.empty()) {
      const int idx = q.front();
      q.pop_front();
      const int u = idx % W, v = idx / W;
      const int l = labels.at<int>(v, u);
      const float z = depth.at<float>(v, u);
      const int nu[4] = {u - 1, u + 1, u, u}, nv[4] = {v, v, v - 1, v + 1};
      for (int k = 0; k < 4; ++k) {
        if (nu[k] < 0 || nv[k] < 0 || nu[k] >= W || nv[k] >= H) continue;
        int& nl = labels.at<int>(nv[k], nu[k]);
        const float nz = depth.at<float>(nv[k], nu[k]);
        if (nl >= 0 || !validDepth(nz) || !continuous(z, nz, max_rel)) continue;
        nl = l;
        q.push_back(nv[k] * W + nu[k]);
      }
    }
  };
  grow(queue);
  for (int v = 0; v < H; ++v)
    for (int u = 0; u < W; ++u)
      if (labels.at<int>(v, u) < 0 && validDepth(depth.at<float>(v, u))) {
        labels.at<int>(v, u) = num_clusters++;
        queue.push_back(v * W + u);
        grow(queue);
      }
}

ClusterGraph buildClusterGraph(cv::Mat labels, int num_labels, const cv::Mat& depth, const CameraIntrinsics& camera,
                               double max_rel, int min_contacts, const std::vector<std::pair<int, int>>& extra_edges) {
  std::vector<int> count(num_labels, 0);
  for (int v = 0; v < labels.rows; ++v) {
    const int* l = labels.ptr<int>(v);
    for (int u = 0; u < labels.cols; ++u)
      if (l[u] >= 0) ++count[l[u]];
  }
  std::vector<int> remap(num_labels, -1);
  ClusterGraph g;
  for (int i = 0; i < num_labels; ++i)
    if (count[i] > 0) remap[i] = g.num_clusters++;
  const int n = g.num_clusters;
  g.sizes.assign(n, 0);
  std::vector<double> zsum(n, 0.0);
  std::vector<Eigen::Vector3d> psum(n, Eigen::Vector3d::Zero());  // sums of (u z, v z, z)
  std::vector<std::uint64_t> contacts;
  auto key = [](int a, int b) {
    return (static_cast<std::uint64_t>(std::min(a, b)) << 32) | static_cast<std::uint32_t>(std::max(a, b));
  };
  for (int v = 0; v < labels.rows; ++v) {
    int* l = labels.ptr<int>(v);
    const float* z = depth.ptr<float>(v);
    for (int u = 0; u < labels.cols; ++u) {
      if (l[u] < 0) continue;
      const int c = l[u] = remap[l[u]];
      ++g.sizes[c];
      zsum[c] += z[u];
      psum[c] += Eigen::Vector3d(u * z[u], v * z[u], z[u]);
    }
  }
  // Second pass once all labels are renumbered.
  for (int v = 0; v < labels.rows; ++v) {
    const int* l = labels.ptr<int>(v);
    const int* ld = v + 1 < labels.rows ? labels.ptr<int>(v + 1) : nullptr;
    const float* z = depth.ptr<float>(v);
    const float* zd = ld ? depth.ptr<float>(v + 1) : nullptr;
    for (int u = 0; u < labels.cols; ++u) {
      if (l[u] < 0) continue;
      if (u + 1 < labels.cols && l[u + 1] >= 0 && l[u + 1] != l[u] && continuous(z[u], z[u + 1], max_rel))
        contacts.push_back(key(l[u], l[u + 1]));
      if (ld && ld[u] >= 0 && ld[u] != l[u] && continuous(z[u], zd[u], max_rel)) contacts.push_back(key(l[u], ld[u]));
    }
  }
  std::sort(contacts.begin(), contacts.end());
  std::vector<std::uint64_t> edge_keys;
  for (size_t i = 0; i < contacts.size();) {
    size_t j = i;
    while (j < contacts.size() && contacts[j] == contacts[i]) ++j;
    if (static_cast<int>(j - i) >= min_contacts) edge_keys.push_back(contacts[i]);
    i = j;
  }
  for (const auto& [a, b] : extra_edges) {
    if (a < 0 || b < 0 || a >= num_labels || b >= num_labels) continue;
    const int ra = remap[a], rb = remap[b];
    if (ra >= 0 && rb >= 0 && ra != rb) edge_keys.push_back(key(ra, rb));
  }
  std::sort(edge_keys.begin(), edge_keys.end());
  edge_keys.erase(std::unique(edge_keys.begin(), edge_keys.end()), edge_keys.end());
  for (auto k : edge_keys) g.edges.emplace_back(static_cast<int>(k >> 32), static_cast<int>(k & 0xffffffffu));
  g.mean_depth.resize(n);
  g.centroids.resize(n);
  for (int c = 0; c < n; ++c) {
    g.mean_depth[c] = static_cast<float>(zsum[c] / g.sizes[c]);
    const Eigen::Vector3d m = psum[c] / g.sizes[c];
    g.centroids[c] = Eigen::Vector3f((m.x() - camera.cx * m.z()) / camera.fx, (m.y() - camera.cy * m.z()) / camera.fy,
                                     m.z());
  }
  g.labels = labels;
  return g;
}

}  // namespace detail
}  // namespace ff
