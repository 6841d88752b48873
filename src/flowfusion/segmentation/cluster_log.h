#pragma once
// What each cluster of a scored frame showed and how it was scored: the cluster means of the
// residual images behind Eq. 10, the resulting delta and score. It answers "why is this marked, or
// not" for a frame of one's own camera (`flowfusion run --cluster-log`), as the per-cluster traces
// behind docs/tuning.md were made. Written per frame as a CSV (docs/formats.md) beside the clusters'
// label image, which ties the rows to pixels.
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "flowfusion/segmentation/clustering.h"
#include "flowfusion/segmentation/dynamic_score.h"

namespace ff {

struct ClusterRecord {
  int pixels = 0;
  double u_px = 0, v_px = 0;  // centroid in the segmentation level's pixels
  double depth_m = 0;         // mean depth
  // Means of |value| over the cluster's pixels where the image is finite; NaN where none is (the
  // term was left out) or where the frame had no such image.
  double r_I = 0;    // intensity residual, [0, 1] grey units
  double r_D_m = 0;  // depth residual against the target
  double r_F_px = 0;  // flow residual against the camera's motion, input pixels
  double r_M_m = 0;  // how far in front of the static map
  double a_M = 0;    // share agreeing with the stable map
  double prior = 0;  // the previous scores carried here
  double memory = 0;  // share remembered as moving (scores.model_memory_s)
  double delta = 0;  // Eq. 10 with the terms kept; NaN: no evidence
  double b = 0;      // the dynamic score
  bool moving = false;  // dynamic with motion evidence now and in the previous frame
};

struct ClusterLog {
  cv::Mat labels;  // CV_32S at the segmentation level: row index of `clusters`, -1 = none (no depth)
  std::vector<ClusterRecord> clusters;
  bool empty() const { return clusters.empty(); }
};

// The records of `graph`'s clusters from the residuals and scores of the frame's last round.
// Throws InputError as clusterMeans does on mismatched images.
ClusterLog clusterLog(const ClusterGraph& graph, const ResidualImages& residuals, const DynamicScores& scores);

// One header line and one line per cluster, comma-separated, NaN written as "nan".
std::string clusterLogCsv(const ClusterLog& log);

}  // namespace ff
