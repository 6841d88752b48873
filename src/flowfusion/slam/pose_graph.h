#pragma once
// A pose graph over keyframes, solved with Ceres (Levenberg-Marquardt, sparse Cholesky): nodes are
// poses T_world_node, an edge measures T_from_to and contributes the whitened error
//   e = [ (t / sigma_m) ; (2 vec(q) / sigma_rad) ]  of  T_from_to^-1 * T_world_from^-1 * T_world_to,
// (q its rotation as a unit quaternion, t its translation), the 3D pose graph of Ceres' examples.
// An edge may go through a Cauchy loss (its robust_scale, in standard deviations): loops, which
// may be wrong, and odometry, which jumps where the tracking went wrong. Node 0 is held fixed (the
// world frame of the first keyframe), or the first PoseGraphOptions::fixed_nodes.
#include <vector>

#include "flowfusion/core/se3.h"

namespace ff {

struct PoseGraphEdge {
  int from = 0, to = 0;
  SE3 T_from_to = SE3::Identity();
  double sigma_m = 0.01;    // standard deviation of the translation, metres
  double sigma_rad = 0.01;  // of the rotation, radians
  double robust_scale = 0;  // Cauchy loss scale in standard deviations; 0: none (quadratic)
};

struct PoseGraphOptions {
  int max_iterations = 100;
  // Nodes 0 .. fixed_nodes - 1 are held where they are (at least node 0): the world frame, and a
  // reused map's keyframes (slam/map_file.h), which this run continues in.
  int fixed_nodes = 1;
};

// The optimised poses, as many as `initial`. Throws InputError on an edge naming a missing node,
// and when the build has no Ceres (loopClosureAvailable() false).
std::vector<SE3> optimizePoseGraph(const std::vector<SE3>& initial, const std::vector<PoseGraphEdge>& edges,
                                   const PoseGraphOptions& options = {});

}  // namespace ff
