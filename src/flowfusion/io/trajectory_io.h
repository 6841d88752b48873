#pragma once
// Trajectories in the TUM RGB-D benchmark format: "timestamp tx ty tz qx qy qz qw" per line,
// camera-to-world (T_world_cam), '#' comments.
#include <string>
#include <vector>

#include "flowfusion/core/se3.h"

namespace ff {

struct StampedPose {
  double timestamp = 0;  // seconds
  SE3 T_world_cam = SE3::Identity();
};
using Trajectory = std::vector<StampedPose>;

// Throws InputError naming the file and line on a missing file, a malformed line, a
// non-unit quaternion, or timestamps that are not strictly increasing.
Trajectory readTrajectory(const std::string& path);
void writeTrajectory(const std::string& path, const Trajectory& traj);

// Pose at time t, interpolated between the two nearest samples; nullopt-like false when t is
// outside the trajectory or the bracketing samples are more than max_gap seconds apart.
bool interpolatePose(const Trajectory& traj, double t, SE3& out, double max_gap = 0.1);

}  // namespace ff
