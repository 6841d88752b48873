#include "flowfusion/slam/loop_verifier.h"

#include <cmath>

namespace ff {

namespace {

// Share of the source's static pixels with depth whose residuals lie within the inlier bounds.
double inlierFraction(const PixelResiduals& r, const cv::Mat& source_depth, const cv::Mat& source_weight,
                      const SlamConfig& config) {
  int considered = 0, inliers = 0;
  for (int y = 0; y < source_depth.rows; ++y)
    for (int x = 0; x < source_depth.cols; ++x) {
      const float z = source_depth.at<float>(y, x);
      if (!(z > 0) || source_weight.at<float>(y, x) < 0.5f) continue;
      ++considered;
      const float ri = r.abs_intensity.at<float>(y, x), rd = r.abs_depth.at<float>(y, x);
      inliers += ri < config.inlier_intensity && rd < config.inlier_depth_m * std::max(1.0f, z);
    }
  return considered > 0 ? static_cast<double>(inliers) / considered : 0.0;
}

}  // namespace

LoopCheck verifyLoop(const KeyframeImages& query, const KeyframeImages& candidate,
                     const SE3& T_candidate_query_guess, const OdometryConfig& odometry, const SlamConfig& config) {
  OdometryConfig at_level = odometry;
  at_level.finest_level = 0;
  // A loop's guess is off by the drift, more than a frame's motion.
  at_level.max_translation = std::max(odometry.max_translation, config.max_correction_m);
  at_level.max_rotation_deg = std::max(odometry.max_rotation_deg, config.max_correction_deg);
  const OdometryFrame source = query.odometryFrame(at_level);
  const OdometryFrame target = candidate.odometryFrame(at_level);
  const cv::Mat source_weight = query.staticWeights(), target_weight = candidate.staticWeights();
  LoopCheck check;
  const OdometryResult r =
      DenseOdometry(at_level).estimate(source, target, T_candidate_query_guess, source_weight, target_weight);
  if (!r.ok) {
    check.reason = "odometry: " + r.message;
    return check;
  }
  check.T_candidate_query = r.T_target_source;
  const SE3 moved = T_candidate_query_guess.inverse() * r.T_target_source;
  if (translationNorm(moved) > config.max_correction_m || rotationAngleDeg(moved) > config.max_correction_deg) {
    check.reason = "the loop moves the keyframe beyond slam.max_correction_m / max_correction_deg";
    return check;
  }
  const PixelResiduals residuals =
      computePixelResiduals(source, target, r.T_target_source, 0, at_level, target_weight, 0, 0, r.target_depth_offset);
  check.inlier_fraction = inlierFraction(residuals, source.level(0).depth, source_weight, config);
  if (check.inlier_fraction < config.min_inlier_fraction) {
    check.reason = "inlier fraction " + std::to_string(check.inlier_fraction) + " below slam.min_inlier_fraction";
    return check;
  }
  if (config.backward_check) {
    const OdometryResult back =
        DenseOdometry(at_level).estimate(target, source, r.T_target_source.inverse(), target_weight, source_weight);
    if (!back.ok) {
      check.reason = "the alignment run back: " + back.message;
      return check;
    }
    const SE3 gap = back.T_target_source * r.T_target_source;  // the identity where both agree
    check.backward_gap_m = translationNorm(gap);
    const double gap_deg = rotationAngleDeg(gap);
    if (check.backward_gap_m > config.loop_sigma_m || gap_deg > config.loop_sigma_deg) {
      check.reason = "the alignment run back lands " + std::to_string(check.backward_gap_m) + " m, " +
                     std::to_string(gap_deg) + " deg from it, beyond slam.loop_sigma_m / loop_sigma_deg";
      return check;
    }
  }
  check.accepted = true;
  return check;
}

}  // namespace ff
