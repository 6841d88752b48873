#include "flowfusion/io/trajectory_io.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "flowfusion/core/atomic_file.h"
#include "flowfusion/core/error.h"
#include "flowfusion/io/tum_text.h"

namespace ff {

Trajectory readTrajectory(const std::string& path) {
  RecordReader in(path, "trajectory file", "timestamp tx ty tz qx qy qz qw");
  Trajectory traj;
  while (in.next()) {
    const double t = in.timestamp();
    double v[7];
    for (double& x : v)
      if (!(in.fields() >> x) || !std::isfinite(x)) in.malformed();
    const Eigen::Quaterniond q(v[6], v[3], v[4], v[5]);
    if (std::abs(q.norm() - 1.0) > 1e-2)
      in.fail("quaternion is not of unit length (norm " + std::to_string(q.norm()) + ")");
    traj.push_back({t, poseFromTranslationQuaternion({v[0], v[1], v[2]}, q)});
  }
  if (traj.empty()) in.fail("trajectory file holds no poses");
  return traj;
}

void writeTrajectory(const std::string& path, const Trajectory& traj) {
  std::ostringstream out;
  out << "# timestamp tx ty tz qx qy qz qw (camera-to-world)\n";
  out << std::fixed;
  for (const auto& p : traj) {
    const Eigen::Quaterniond q(p.T_world_cam.rotation());
    const Eigen::Vector3d t = p.T_world_cam.translation();
    out << std::setprecision(6) << p.timestamp << ' ' << std::setprecision(7) << t.x() << ' ' << t.y() << ' '
        << t.z() << ' ' << q.x() << ' ' << q.y() << ' ' << q.z() << ' ' << q.w() << '\n';
  }
  writeFileAtomic(path, out.str(), "trajectory file");
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
