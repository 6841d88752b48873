#pragma once
// Internal helpers shared by the clustering backends (not part of the public API).
#include <opencv2/core.hpp>
#include <utility>
#include <vector>

#include "flowfusion/segmentation/clustering.h"

namespace ff::detail {

inline bool validDepth(float z) { return z > 0.f && z < 1e6f; }

// Throws InputError unless the frame's depth is CV_32FC1 and matches the camera.
void checkClusterInput(const RgbdFrame& frame, const CameraIntrinsics& camera, const std::string& who);

// Gives every valid-depth pixel with label -1 a cluster: grows existing clusters into them
// (4-connected, only across depth-continuous steps), then makes each remaining connected
// region a new cluster. Updates num_clusters.
void fillUnlabeled(cv::Mat& labels, const cv::Mat& depth, double max_rel_depth_jump, int& num_clusters);

// Renumbers labels to 0..n-1 dropping empty ones, fills sizes, mean depths and centroids, and
// the edges: `extra_edges` (in the input numbering) plus clusters touching in the image with
// at least `min_contacts` depth-continuous neighbour pairs.
ClusterGraph buildClusterGraph(cv::Mat labels, int num_labels, const cv::Mat& depth, const CameraIntrinsics& camera,
                               double max_rel_depth_jump, int min_contacts,
                               const std::vector<std::pair<int, int>>& extra_edges = {});

}  // namespace ff::detail
