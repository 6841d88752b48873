#pragma once
// The written dynamic mask without the pixels the static map already holds. A cluster at the
// segmentation level straddles a mover's edge, and a static region next to a mover is held dynamic
// by its neighbours, the carried score and the motion memory; yet a pixel whose depth and grey
// level coincide with the stable map's (modelAgreement, score_evidence.h) is the background the map
// was built from. Only the written mask: the odometry, the fusion and the carried scores keep the
// cluster's score, since a mover fused by mistake (a person sitting still) leaves the map only
// while it is marked there (FusionConfig::dynamic_removal; docs/tuning.md#mask_map_agreement).
#include <opencv2/core.hpp>

namespace ff {

// Clears (0) the pixels of `mask` (CV_8UC1, > 0 = dynamic) where `agreement` (CV_8UC1, > 0 =
// agrees with the map) holds, `agreement` taken at the mask's size by nearest neighbour (it is
// made at the segmentation level). An empty `agreement` (no map yet) leaves the mask as it is.
// Throws InputError on an empty mask or either image of another type.
void clearMapAgreement(cv::Mat& mask, const cv::Mat& agreement);

}  // namespace ff
