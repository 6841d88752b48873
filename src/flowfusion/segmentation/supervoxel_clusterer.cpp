// The paper's over-segmentation: PCL supervoxels (Papon et al., CVPR 2013) on A's point cloud,
// with the grey level standing in for colour.
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/segmentation/supervoxel_clustering.h>

#include "flowfusion/core/error.h"
#include "flowfusion/segmentation/cluster_graph_builder.h"

namespace ff {

namespace {

class SupervoxelClusterer : public Clusterer {
 public:
  explicit SupervoxelClusterer(const ClusteringConfig& c) : config_(c) {}

  std::string name() const override { return "supervoxel"; }

  ClusterGraph cluster(const RgbdFrame& frame, const CameraIntrinsics& camera) override {
    detail::checkClusterInput(frame, camera, "supervoxel clustering");
    const cv::Mat& depth = frame.depth;
    const bool has_intensity = frame.intensity.type() == CV_32FC1 && frame.intensity.size() == depth.size();
    auto cloud = pcl::make_shared<pcl::PointCloud<pcl::PointXYZRGBA>>();
    std::vector<int> pixel_of_point;
    cloud->reserve(depth.total());
    for (int v = 0; v < depth.rows; ++v)
      for (int u = 0; u < depth.cols; ++u) {
        const float z = depth.at<float>(v, u);
        if (!detail::validDepth(z)) continue;
        const Eigen::Vector3d p = camera.backproject(u, v, z);
        pcl::PointXYZRGBA pt;
        pt.x = p.x();
        pt.y = p.y();
        pt.z = p.z();
        const auto g = static_cast<std::uint8_t>(
            has_intensity ? std::clamp(frame.intensity.at<float>(v, u) * 255.f + 0.5f, 0.f, 255.f) : 0.f);
        pt.r = pt.g = pt.b = g;
        pt.a = 255;
        cloud->push_back(pt);
        pixel_of_point.push_back(v * depth.cols + u);
      }

    cv::Mat labels(depth.size(), CV_32S, cv::Scalar(-1));
    int num_labels = 0;
    std::vector<std::pair<int, int>> edges;
    if (!cloud->empty()) {
      pcl::SupervoxelClustering<pcl::PointXYZRGBA> sv(config_.voxel_resolution, config_.seed_resolution);
      // Voxels grow with depth (z-scaled octree), matching the Kinect's range-dependent noise.
      sv.setUseSingleCameraTransform(true);
      sv.setInputCloud(cloud);
      sv.setColorImportance(config_.color_importance);
      sv.setSpatialImportance(config_.spatial_importance);
      sv.setNormalImportance(config_.normal_importance);
      std::map<std::uint32_t, pcl::Supervoxel<pcl::PointXYZRGBA>::Ptr> clusters;
      sv.extract(clusters);
      // PCL labels start at 1; 0 = a voxel no supervoxel reached (filled below).
      const auto labelled = sv.getLabeledCloud();
      for (size_t i = 0; i < labelled->size() && i < pixel_of_point.size(); ++i) {
        const int l = static_cast<int>((*labelled)[i].label);
        labels.at<int>(pixel_of_point[i] / depth.cols, pixel_of_point[i] % depth.cols) = l - 1;
        num_labels = std::max(num_labels, l);
      }
      std::multimap<std::uint32_t, std::uint32_t> adjacency;
      sv.getSupervoxelAdjacency(adjacency);
      for (const auto& [a, b] : adjacency) edges.emplace_back(static_cast<int>(a) - 1, static_cast<int>(b) - 1);
    }
    detail::fillUnlabeled(labels, depth, config_.adjacency_max_rel_depth_jump, num_labels);
    // Edges: PCL's voxel adjacency plus clusters touching in the image (which also connects
    // clusters created by the fill).
    return detail::buildClusterGraph(labels, num_labels, depth, camera, config_.adjacency_max_rel_depth_jump,
                                     config_.adjacency_min_contacts, edges);
  }

 private:
  ClusteringConfig config_;
};

}  // namespace

std::unique_ptr<Clusterer> makeSupervoxelClusterer(const ClusteringConfig& config) {
  return std::make_unique<SupervoxelClusterer>(config);
}

}  // namespace ff
