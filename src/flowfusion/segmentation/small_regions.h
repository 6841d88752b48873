#pragma once
// The written dynamic mask without small marks inside the view. On real frames the scores leave
// marks of one or two clusters where blur, a depth edge or the colour-depth time offset gives a
// static cluster a residual of its own, frame after frame, with nothing around it marked. A mover
// within the depth sensor's range covers more of the image (a person at 6 m about 2 % of it), and
// one entering the view is a slice of any size at first, but across the image's border. A small
// mover inside the view (a box 2 m away, a person half hidden) is kept where the scores have seen
// it move with a flow of its own, away from the static map (seenMovingClusters).
#include <opencv2/core.hpp>

#include "flowfusion/segmentation/dynamic_score.h"

namespace ff {

// Clears (0) every 8-connected dynamic region of `mask` (CV_8UC1, > 0 = dynamic) that holds fewer
// than `min_area_share` (in [0, 1); 0 keeps all) of the image's pixels and touches no image border,
// unless more than half of its pixels are non-zero in `keep` (CV_8UC1, the mask's size; empty: none).
// Throws InputError on an empty mask, another type, a share outside [0, 1) or a `keep` that does
// not match.
void dropSmallInteriorRegions(cv::Mat& mask, double min_area_share, const cv::Mat& keep = {});

// 255 on the pixels of the clusters seen moving (DynamicScores::moving: dynamic in this frame and
// the previous one, in a group with motion evidence) whose mean flow residual r_F is at least
// `min_flow_px` pixels and less than `max_map_agreement` of whose pixels coincide with the stable
// static map (a_M; none when there is no map); 0 elsewhere (CV_8UC1, graph.labels' size). On real
// frames such clusters are movers about nine times in ten, the other small marks one in eight
// (docs/tuning.md#mask_keep_flow_px). `min_flow_px` 0: no cluster.
cv::Mat seenMovingClusters(const ClusterGraph& graph, const ResidualImages& residuals, const DynamicScores& scores,
                           double min_flow_px, double max_map_agreement);

}  // namespace ff
