#pragma once
// Trajectory error metrics of the TUM RGB-D benchmark, numerically equal to its scripts
// evaluate_ate.py (absolute trajectory error) and evaluate_rpe.py --fixed_delta (relative pose
// error, delta in seconds), so that numbers can be compared with published tables.
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "flowfusion/io/trajectory_io.h"

namespace ff::eval {

// Statistics of a list of errors as the scripts print them (std is numpy's population std).
struct ErrorStats {
  double rmse = 0, mean = 0, median = 0, std = 0, min = 0, max = 0;
};
// Throws std::invalid_argument on an empty list (callers check counts first).
ErrorStats errorStats(const std::vector<double>& errors);
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(ErrorStats, rmse, mean, median, std, min, max)

// The scripts' association (associate.py as evaluate_ate.py uses it): ff::associate with the
// difference strictly below max_diff_s (StampLimit::kExclusive).
std::vector<std::pair<size_t, size_t>> associateStamps(const std::vector<double>& a, const std::vector<double>& b,
                                                       double max_diff_s);

// The trajectory with offset_s seconds added to every timestamp, as evaluate_ate.py and
// evaluate_rpe.py --offset do to their second file: a camera whose stamps are out of step with the
// ground truth's clock (TUM's Kinect frames are stamped on arrival) is compared at its own time.
// Throws InputError (naming --offset) when offset_s is not finite.
Trajectory withTimeOffset(Trajectory trajectory, double offset_s);

struct AteResult {
  size_t matched_poses = 0;  // associated (GT, EST) pairs
  ErrorStats translation_m;  // per-pose distance between GT and aligned EST positions
  SE3 T_gt_est = SE3::Identity();  // the Horn alignment applied to the estimate (no scale)
};
void to_json(nlohmann::json& j, const AteResult& r);

struct RpeResult {
  size_t pairs = 0;           // compared pose pairs
  double delta_s = 1.0;       // pair spacing
  ErrorStats translation_m;   // per pair, metres over delta_s (what evaluate_rpe.py prints)
  ErrorStats rotation_deg;    // per pair, degrees over delta_s
  double translation_rmse_m_per_s = 0;  // translation_m.rmse / delta_s (the papers' "m/s")
  double rotation_rmse_deg_per_s = 0;   // rotation_deg.rmse / delta_s
};
void to_json(nlohmann::json& j, const RpeResult& r);

// ATE as evaluate_ate.py GT EST (offset 0, scale 1): associate GT (first list) with EST within
// max_diff_s, align EST positions onto GT in closed form (Horn/Kabsch, rotation + translation),
// statistics of the remaining position errors. gt_name/est_name (file names) go into errors:
// InputError when fewer than 3 poses associate or max_diff_s is not positive.
// With AteAlignment::None the estimate is compared as it stands (T_gt_est identity, one pose is
// enough): for a run that claims to be in the ground truth's world frame (`run --map-in` in a map
// whose run started at the ground truth's pose).
enum class AteAlignment { Horn, None };
AteResult computeAte(const Trajectory& gt, const Trajectory& est, double max_diff_s = 0.02,
                     const std::string& gt_name = "ground truth", const std::string& est_name = "estimate",
                     AteAlignment alignment = AteAlignment::Horn);

// RPE as evaluate_rpe.py GT EST --fixed_delta --delta delta_s --delta_unit s --max_pairs 0 (every
// pair, no random subsampling): for every estimated pose i, j = the estimated pose whose stamp is
// closest to t_i + delta_s (pairs with j = the last pose are skipped, as the script does); each
// stamp is matched with the closest GT stamp, and pairs whose GT stamps are more than twice the
// median GT interval away are dropped. Error E = (inv(E_j) E_i)^-1 (inv(G_j) G_i): translation
// norm and rotation angle. O(n log n): every closest stamp is a binary search. InputError naming
// the files when delta_s is not positive, finite and shorter than the estimate, when the
// trajectories do not overlap in time, or when fewer than 2 pairs remain.
RpeResult computeRpe(const Trajectory& gt, const Trajectory& est, double delta_s = 1.0,
                     const std::string& gt_name = "ground truth", const std::string& est_name = "estimate");

}  // namespace ff::eval
