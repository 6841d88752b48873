#pragma once
// A pose graph over keyframes, solved with Ceres (Levenberg-Marquardt, sparse Cholesky): nodes are
// poses T_world_node, an edge measures T_from_to and contributes the whitened error
//   e = [ (t / sigma_m) ; (2 vec(q) / sigma_rad) ]  of  T_from_to^-1 * T_world_from^-1 * T_world_to,
// (q its rotation as a unit quaternion, t its translation), the 3D pose graph of Ceres' examples.
// Robust edges (loops, which may be wrong) go through a Cauchy loss of scale robust_scale; node 0
// is held fixed (the world frame of the first keyframe), or the first PoseGraphOptions::fixed_nodes.
#include <vector>

#include "flowfusion/core/se3.h"

namespace ff {

struct PoseGraphEdge {
  int from = 0, to = 0;
  SE3 T_from_to = SE3::Identity();
  double sigma_m = 0.01;    // standard deviation of the translation, metres
  double sigma_rad = 0.01;  // of the rotation, radians
  bool robust = false;      // through the Cauchy loss
};

struct PoseGraphOptions {
  double robust_scale = 2.0;  // Cauchy scale, in standard deviations
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
