#include "flowfusion/io/trajectory_io.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "flowfusion/core/error.h"

namespace ff {

Trajectory readTrajectory(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open trajectory file");
  Trajectory traj;
  std::string line;
  int lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream ss(line);
    double v[8];
    for (double& x : v)
      if (!(ss >> x) || !std::isfinite(x))
        throw InputError(path + ":" + std::to_string(lineno) +
                         ": expected 'timestamp tx ty tz qx qy qz qw' (8 finite numbers)");
    const Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
    if (std::abs(q.norm() - 1.0) > 1e-2)
      throw InputError(path + ":" + std::to_string(lineno) + ": quaternion is not of unit length (norm " +
                       std::to_string(q.norm()) + ")");
    if (!traj.empty() && v[0] <= traj.back().timestamp)
      throw InputError(path + ":" + std::to_string(lineno) + ": timestamp " + std::to_string(v[0]) +
                       " is not after the previous one (timestamps must be strictly increasing)");
    traj.push_back({v[0], poseFromTranslationQuaternion({v[1], v[2], v[3]}, q)});
  }
  if (traj.empty()) throw InputError(path + ": trajectory file holds no poses");
  return traj;
}

void writeTrajectory(const std::string& path, const Trajectory& traj) {
  std::ofstream out(path);
  if (!out) throw InputError(path + ": cannot write trajectory file");
  out << "# timestamp tx ty tz qx qy qz qw (camera-to-world)\n";
  out << std::fixed;
  for (const auto& p : traj) {
    const Eigen::Quaterniond q(p.T_world_cam.rotation());
    const Eigen::Vector3d t = p.T_world_cam.translation();
    out << std::setprecision(6) << p.timestamp << ' ' << std::setprecision(7) << t.x() << ' ' << t.y() << ' '
        << t.z() << ' ' << q.x() << ' ' << q.y() << ' ' << q.z() << ' ' << q.w() << '\n';
  }
  if (!out) throw InputError(path + ": error while writing trajectory file");
}

bool interpolatePose(const Trajectory& traj, double t, SE3& out, double max_gap) {
  if (traj.empty() || t < traj.front().timestamp || t > traj.back().timestamp) return false;
  auto it = std::lower_bound(traj.begin(), traj.end(), t,
                             [](const StampedPose& p, double ts) { return p.timestamp < ts; });
  if (it->timestamp == t) {
    out = it->T_world_cam;
    return true;
  }
  const auto& b = *it;
  const auto& a = *(it - 1);
  if (b.timestamp - a.timestamp > max_gap) return false;
  out = interpolate(a.T_world_cam, b.T_world_cam, (t - a.timestamp) / (b.timestamp - a.timestamp));
  return true;
}

}  // namespace ff
