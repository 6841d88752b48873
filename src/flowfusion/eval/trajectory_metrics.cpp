#include "flowfusion/eval/trajectory_metrics.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "flowfusion/core/error.h"
#include "flowfusion/eval/bench_utils.h"
#include "flowfusion/io/tum_text.h"

namespace ff::eval {

namespace {

std::string fmt(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6f", v);
  return buf;
}

// %g: short also for 1e300.
std::string fmtShort(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

std::vector<double> stampsOf(const Trajectory& t) {
  std::vector<double> s;
  s.reserve(t.size());
  for (const auto& p : t) s.push_back(p.timestamp);
  return s;
}

// evaluate_rpe.py's find_closest_index: a binary search that keeps the closest element seen on
// its path. Both neighbours of t lie on that path, so this is the closest element; on an exact
// tie the one visited first wins, which we reproduce by following the same path.
size_t closestIndex(const std::vector<double>& sorted, double t) {
  size_t begin = 0, end = sorted.size(), best = 0;
  double diff = std::abs(sorted[0] - t);
  while (begin < end) {
    const size_t middle = (begin + end) / 2;
    if (std::abs(sorted[middle] - t) < diff) {
      diff = std::abs(sorted[middle] - t);
      best = middle;
    }
    if (sorted[middle] == t) return middle;
    if (sorted[middle] > t) end = middle;
    else begin = middle + 1;
  }
  return best;
}

// Rotation angle as the scripts compute it (arccos of the clamped trace), radians.
double angleRad(const Eigen::Matrix3d& R) { return std::acos(std::clamp((R.trace() - 1.0) / 2.0, -1.0, 1.0)); }

}  // namespace

ErrorStats errorStats(const std::vector<double>& errors) {
  if (errors.empty()) throw std::invalid_argument("errorStats: no errors");
  ErrorStats s;
  const double n = static_cast<double>(errors.size());
  double sum = 0, sum_sq = 0;
  for (double e : errors) {
    sum += e;
    sum_sq += e * e;
  }
  s.mean = sum / n;
  s.rmse = std::sqrt(sum_sq / n);
  double var = 0;
  for (double e : errors) var += (e - s.mean) * (e - s.mean);
  s.std = std::sqrt(var / n);
  s.median = median(errors);
  const auto [lo, hi] = std::minmax_element(errors.begin(), errors.end());
  s.min = *lo;
  s.max = *hi;
  return s;
}

std::vector<std::pair<size_t, size_t>> associateStamps(const std::vector<double>& a, const std::vector<double>& b,
                                                       double max_diff_s) {
  return associate(a, b, max_diff_s, StampLimit::kExclusive);
}

void to_json(nlohmann::json& j, const AteResult& r) {
  const Eigen::Quaterniond q(r.T_gt_est.rotation());
  const Eigen::Vector3d t = r.T_gt_est.translation();
  j = {{"matched_poses", r.matched_poses},
       {"translation_m", r.translation_m},
       {"T_gt_est", {{"t", {t.x(), t.y(), t.z()}}, {"q_xyzw", {q.x(), q.y(), q.z(), q.w()}}}}};
}

void to_json(nlohmann::json& j, const RpeResult& r) {
  j = {{"pairs", r.pairs},
       {"delta_s", r.delta_s},
       {"translation_m", r.translation_m},
       {"rotation_deg", r.rotation_deg},
       {"translation_rmse_m_per_s", r.translation_rmse_m_per_s},
       {"rotation_rmse_deg_per_s", r.rotation_rmse_deg_per_s}};
}

Trajectory withTimeOffset(Trajectory trajectory, double offset_s) {
  if (!std::isfinite(offset_s)) throw InputError("--offset: must be a finite number of seconds");
  for (StampedPose& p : trajectory) p.timestamp += offset_s;
  return trajectory;
}

AteResult computeAte(const Trajectory& gt, const Trajectory& est, double max_diff_s, const std::string& gt_name,
                     const std::string& est_name, AteAlignment alignment) {
  if (!(max_diff_s > 0)) throw InputError("--max-diff: must be positive, got " + fmtShort(max_diff_s));
  const auto matches = associateStamps(stampsOf(gt), stampsOf(est), max_diff_s);
  const size_t needed = alignment == AteAlignment::Horn ? 3 : 1;
  if (matches.size() < needed)
    throw InputError(gt_name + " vs " + est_name + ": only " + std::to_string(matches.size()) +
                     " poses have timestamps within " + fmt(max_diff_s) + " s of each other (at least " +
                     std::to_string(needed) + (needed > 1 ? " are needed to align the trajectories" : " is needed") +
                     "; do they cover the same sequence?)");
  const Eigen::Index n = static_cast<Eigen::Index>(matches.size());
  Eigen::Matrix3Xd model(3, n), data(3, n);  // model = EST, data = GT, as align(second, first)
  for (Eigen::Index k = 0; k < n; ++k) {
    const auto [i, j] = matches[static_cast<size_t>(k)];
    data.col(k) = gt[i].T_world_cam.translation();
    model.col(k) = est[j].T_world_cam.translation();
  }
  const Eigen::Vector3d model_mean = model.rowwise().mean();
  const Eigen::Vector3d data_mean = data.rowwise().mean();
  const Eigen::Matrix3d W = (model.colwise() - model_mean) * (data.colwise() - data_mean).transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(W.transpose(), Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0) S(2, 2) = -1;
  const Eigen::Matrix3d R = svd.matrixU() * S * svd.matrixV().transpose();

  AteResult r;
  r.matched_poses = matches.size();
  if (alignment == AteAlignment::Horn) {
    r.T_gt_est.linear() = R;
    r.T_gt_est.translation() = data_mean - R * model_mean;
  }
  std::vector<double> err(matches.size());
  for (Eigen::Index k = 0; k < n; ++k)
    err[static_cast<size_t>(k)] = (r.T_gt_est * Eigen::Vector3d(model.col(k)) - data.col(k)).norm();
  r.translation_m = errorStats(err);
  return r;
}

RpeResult computeRpe(const Trajectory& gt, const Trajectory& est, double delta_s, const std::string& gt_name,
                     const std::string& est_name) {
  if (!(delta_s > 0) || !std::isfinite(delta_s))
    throw InputError("--delta: must be a positive number of seconds, got " + fmtShort(delta_s));
  if (gt.size() < 2) throw InputError(gt_name + ": at least 2 ground-truth poses are needed for RPE");
  if (est.size() < 2) throw InputError(est_name + ": at least 2 estimated poses are needed for RPE");
  const double span_s = est.back().timestamp - est.front().timestamp;
  if (delta_s >= span_s)
    throw InputError("--delta: " + fmtShort(delta_s) + " s is not shorter than " + est_name + " (" + fmt(span_s) +
                     " s from its first to its last pose)");
  const auto stamps_gt = stampsOf(gt);
  const auto stamps_est = stampsOf(est);

  // The script's overlap test: estimated stamps that survive a round trip to the closest GT stamp
  // and back; without overlap in time they all collapse onto one end.
  // Each lookup is a binary search and distinct targets are counted with flags: O(n log n).
  std::vector<char> reached(stamps_est.size(), 0);
  size_t round_trip = 0;
  for (double t : stamps_est) {
    const size_t k = closestIndex(stamps_est, stamps_gt[closestIndex(stamps_gt, t)]);
    round_trip += !reached[k];
    reached[k] = 1;
  }
  if (round_trip < 2)
    throw InputError(gt_name + " vs " + est_name +
                     ": the trajectories do not overlap in time (did you pass the right files?)");

  std::vector<double> intervals;
  for (size_t k = 1; k < stamps_gt.size(); ++k) intervals.push_back(stamps_gt[k] - stamps_gt[k - 1]);
  const double gt_max_time_difference = 2 * median(intervals);

  std::vector<double> trans, rot;
  for (size_t i = 0; i < est.size(); ++i) {
    const size_t j = closestIndex(stamps_est, stamps_est[i] + delta_s);
    if (j == est.size() - 1) continue;
    const size_t g0 = closestIndex(stamps_gt, stamps_est[i]);
    const size_t g1 = closestIndex(stamps_gt, stamps_est[j]);
    if (std::abs(stamps_gt[g0] - stamps_est[i]) > gt_max_time_difference ||
        std::abs(stamps_gt[g1] - stamps_est[j]) > gt_max_time_difference)
      continue;
    const SE3 est_rel = est[j].T_world_cam.inverse() * est[i].T_world_cam;
    const SE3 gt_rel = gt[g1].T_world_cam.inverse() * gt[g0].T_world_cam;
    const SE3 error = est_rel.inverse() * gt_rel;
    trans.push_back(error.translation().norm());
    rot.push_back(angleRad(error.linear()) * 180.0 / M_PI);
  }
  if (trans.size() < 2)
    throw InputError(gt_name + " vs " + est_name + ": only " + std::to_string(trans.size()) +
                     " pose pairs " + fmt(delta_s) +
                     " s apart match the ground truth (at least 2 are needed; is the estimate shorter than "
                     "--delta or far from the ground-truth timestamps?)");
  RpeResult r;
  r.pairs = trans.size();
  r.delta_s = delta_s;
  r.translation_m = errorStats(trans);
  r.rotation_deg = errorStats(rot);
  r.translation_rmse_m_per_s = r.translation_m.rmse / delta_s;
  r.rotation_rmse_deg_per_s = r.rotation_deg.rmse / delta_s;
  return r;
}

}  // namespace ff::eval
