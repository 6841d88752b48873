// The trajectory section: the estimate aligned onto the ground truth, per-pose errors, ATE, RPE.
#include <cmath>

#include "flowfusion/core/error.h"
#include "flowfusion/eval/trajectory_metrics.h"
#include "flowfusion/report/report_parts.h"

namespace ff::report {
namespace {

constexpr double kMaxStampDiffS = 0.02;  // association limit, as evaluate_ate.py
constexpr size_t kMaxGtPathPoints = 3000;

nlohmann::json xyz(const Eigen::Vector3d& p) {
  // Millimetre precision is plenty for a plot and keeps the page small.
  return {std::round(p.x() * 1e4) / 1e4, std::round(p.y() * 1e4) / 1e4, std::round(p.z() * 1e4) / 1e4};
}

// The ground-truth positions over the estimate's time span (a second either side), thinned to a bound.
nlohmann::json gtPath(const Trajectory& gt, double t0, double t1) {
  std::vector<Eigen::Vector3d> path;
  for (const auto& p : gt)
    if (p.timestamp >= t0 - 1.0 && p.timestamp <= t1 + 1.0) path.push_back(p.T_world_cam.translation());
  const size_t stride = path.size() / kMaxGtPathPoints + 1;
  nlohmann::json out = nlohmann::json::array();
  for (size_t i = 0; i < path.size(); i += stride) out.push_back(xyz(path[i]));
  return out;
}

void addRpe(const Trajectory& gt, const Trajectory& est, double delta_s, nlohmann::json& headline) {
  const double span_s = est.back().timestamp - est.front().timestamp;
  const double delta = span_s > 2 * delta_s ? delta_s : span_s / 4;
  try {
    const auto rpe = eval::computeRpe(gt, est, delta);
    headline["rpe_delta_s"] = rpe.delta_s;
    headline["rpe_translation_rmse_m"] = rpe.translation_m.rmse;
    headline["rpe_rotation_rmse_deg"] = rpe.rotation_deg.rmse;
  } catch (const InputError& e) {
    headline["rpe_note"] = e.what();  // e.g. too few poses: the page says why there is no RPE
  }
}

}  // namespace

TrajectorySection trajectorySection(const Trajectory& est, const std::optional<Trajectory>& gt,
                                    double rpe_delta_s, nlohmann::json& headline) {
  TrajectorySection s;
  nlohmann::json& j = s.json;
  j["t"] = nlohmann::json::array();
  j["est"] = nlohmann::json::array();
  if (est.empty()) return s;
  const double t0 = est.front().timestamp;
  std::vector<std::pair<size_t, size_t>> pairs;
  if (gt && !gt->empty()) {
    std::vector<double> gt_stamps, est_stamps;
    for (const auto& p : *gt) gt_stamps.push_back(p.timestamp);
    for (const auto& p : est) est_stamps.push_back(p.timestamp);
    pairs = eval::associateStamps(gt_stamps, est_stamps, kMaxStampDiffS);
  }
  if (pairs.size() >= 3) {
    const auto ate = eval::computeAte(*gt, est, kMaxStampDiffS);
    s.T_gt_est = ate.T_gt_est;
    s.aligned = true;
    headline["ate_rmse_m"] = ate.translation_m.rmse;
    headline["ate_max_m"] = ate.translation_m.max;
    headline["ate_poses"] = ate.matched_poses;
    addRpe(*gt, est, rpe_delta_s, headline);
    j["gt"] = gtPath(*gt, t0, est.back().timestamp);
  } else if (gt) {
    headline["ate_note"] = "the ground truth and the estimate share fewer than 3 timestamps";
  }
  // Position error after the alignment; rotation error as drift since the first associated pose
  // (the alignment fits positions only and leaves the rotation about a straight path undetermined).
  std::vector<nlohmann::json> err_t(est.size()), err_r(est.size());
  for (const auto& [gi, ei] : pairs) {
    if (!s.aligned) break;
    const SE3& truth = (*gt)[gi].T_world_cam;
    err_t[ei] = ((s.T_gt_est * est[ei].T_world_cam).translation() - truth.translation()).norm();
    const Eigen::Matrix3d gt_rel = (*gt)[pairs[0].first].T_world_cam.rotation().transpose() * truth.rotation();
    const Eigen::Matrix3d est_rel =
        est[pairs[0].second].T_world_cam.rotation().transpose() * est[ei].T_world_cam.rotation();
    err_r[ei] = Eigen::AngleAxisd(gt_rel.transpose() * est_rel).angle() * 180.0 / M_PI;
  }
  for (const auto& p : est) {
    j["t"].push_back(std::round((p.timestamp - t0) * 1e4) / 1e4);
    j["est"].push_back(xyz((s.T_gt_est * p.T_world_cam).translation()));
  }
  if (s.aligned) {
    j["err_t_m"] = err_t;
    j["err_r_deg"] = err_r;
  }
  j["aligned"] = s.aligned;
  return s;
}

}  // namespace ff::report
