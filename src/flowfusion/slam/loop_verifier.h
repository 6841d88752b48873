#pragma once
// The geometric check of a loop candidate: the dense odometry (odometry/dense_odometry.h) aligns
// the new keyframe (source) to the candidate (target) from the pose graph's guess, both weighted
// by their static weights, and the loop is accepted when it converged, moved the guess by less
// than the bounds, and enough of the new keyframe's static pixels land on the candidate's surface
// (depth and intensity within the inlier bounds; pixels landing outside its view or on its movers
// count as outliers), and the alignment run back, the candidate to the new keyframe from that
// answer, agrees with it within a loop edge's standard deviations (slam.backward_check). A place
// that only looks alike fails on the geometry; people left unmasked in either keyframe pull the
// two directions apart (loops 16-209 mm off the truth with 66-81 % inliers).
#include <string>

#include "flowfusion/core/se3.h"
#include "flowfusion/odometry/dense_odometry.h"
#include "flowfusion/slam/keyframe.h"
#include "flowfusion/slam/slam_config.h"

namespace ff {

struct LoopCheck {
  bool accepted = false;
  std::string reason;                     // why not, when rejected
  SE3 T_candidate_query = SE3::Identity();  // the odometry's answer
  double inlier_fraction = 0;             // of the query's static pixels with depth
  double backward_gap_m = 0;              // how far the alignment run back lands from it (when run)
};

// `odometry` aligns the keyframes' own level: its finest_level is taken as 0.
LoopCheck verifyLoop(const KeyframeImages& query, const KeyframeImages& candidate,
                     const SE3& T_candidate_query_guess, const OdometryConfig& odometry, const SlamConfig& config);

}  // namespace ff
