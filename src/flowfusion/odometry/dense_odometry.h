#pragma once
// Robust dense RGB-D odometry (FlowFusion Eq. 1-6; Kerl, Sturm, Cremers ICRA 2013).
//
// For every pixel x of the reference frame A with depth, the point p = pi^-1(x, D_A(x)) is moved
// by the motion T_B_A (A's camera frame to B's) and projected into B:
//   r_I = I_B(W(x)) - I_A(x)                (intensity, units of [0, 1] grey)
//   r_D = D_B(W(x)) - [T_B_A p]_z           (depth, metres)
// and  sum_x  v(x) [ C(alpha_I r_I / sigma_I) + C(r_D / sigma_D(x)) ]  is minimised over T_B_A by
// iteratively re-weighted Gauss-Newton, coarse to fine, with the Cauchy penalty
// C(e) = c^2/2 log(1 + (e/c)^2) and v(x) in [0, 1] an optional per-pixel weight of A (FlowFusion
// Eq. 16 passes 1 - b). sigma_D grows with range (Kinect noise model, Nguyen et al. 2012) and with
// the local depth slope, so that depth edges and far surfaces count less.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "flowfusion/core/camera.h"
#include "flowfusion/core/image_pyramid.h"
#include "flowfusion/core/se3.h"

namespace ff {

struct OdometryConfig {
  int levels = 4;            // pyramid levels (level l is 2^l times smaller than the input)
  int finest_level = 1;      // finest level used; 1 (320x240 for VGA) halves the cost of level 0
                             // for no measured loss of accuracy on fr1/xyz
  int max_iterations = 6;    // Gauss-Newton iterations per coarse level at most (they are cheap)
  int max_iterations_finest = 2;  // at the finest level, where an iteration costs 4x the one below
  double alpha_I = 0.9;      // weight of the intensity term (paper, Table III)
  double sigma_I = 0.3;      // intensity scale, [0, 1] grey units: r_I is divided by it. Large on
                             // purpose: fr1/xyz ATE 0.0239 m at 0.04, 0.0164 m at 0.3 (exposure
                             // changes and colour-depth misregistration make intensity the weaker cue)
  double cauchy_c = 1.0;     // Cauchy scale for the normalised residuals (dimensionless)
  bool use_intensity = true;
  bool use_depth = true;
  double depth_sigma_a = 0.0012;  // m, sigma_D(z) = a + b (z - 0.4)^2 (Nguyen et al. 2012)
  double depth_sigma_b = 0.0019;  // 1/m
  double depth_slope_sigma = 1.0; // px of misregistration assumed: adds slope * this to sigma_D
                                  // (fr1/xyz ATE: 0.072 m at 0, 0.0164 m at 1)
  double min_depth = 0.2;    // m, depths outside [min_depth, max_depth] are ignored
  double max_depth = 6.0;    // m
  double convergence_eps = 1e-6;  // stop a level when the update's norm (m, rad) falls below
  // A reference pixel whose warped point lies behind the target's surface by more than this
  // fraction of its depth is hidden in the target (background uncovered by a moving or near
  // object): its intensity and depth there belong to the occluder, so it is left out of the
  // alignment and of computePixelResiduals (0 = keep it). Without this, the uncovered background
  // beside a moving object was scored dynamic (the paper's Eq. 10 compares it with the object)
  // and pulled the odometry. Measured (flowfusion run, defaults otherwise; ATE mm / mean IoU,
  // synth seeds 1-6 of `flowfusion synth --frames 150`, fr1 aug = `flowfusion augment` of the
  // shared frames, seed 1):
  //   occlusion_ratio  seed 1      seed 2      seed 3      seed 4      seed 5      seed 6      fr1 aug
  //   0                3.7 / .845  3.4 / .849  5.6 / .878  1.5 / .811  1.7 / .639  2.3 / .735  14.5 / .658
  //   0.2              3.6 / .921  3.3 / .876  5.3 / .900  1.0 / .869  1.7 / .669  2.6 / .713  14.5 / .654
  //   0.3              3.7 / .922  3.3 / .876  5.2 / .895  0.8 / .869  1.7 / .669  2.4 / .714  14.5 / .663
  //   0.5              3.5 / .921  3.3 / .879  7.1 / .874  1.0 / .866  1.7 / .668  2.4 / .729  14.5 / .660
  // Their static twins (no moving objects): ATE 4.2, 2.6, 1.7, 1.3, 1.2, 0.7 -> 3.5, 2.6, 1.7, 0.7,
  // 1.2, 0.4 mm and dynamic pixels per frame 1327, 632, 0, 395, 4285, 16 -> 1763, 77, 0, 80, 4059,
  // 0 at 0.3; static fr1/xyz 12.9 mm either way.
  double occlusion_ratio = 0.3;
  // Failure detection.
  double min_valid_fraction = 0.05;  // of the finest level's pixels that must take part
  double max_translation = 0.3;      // m per frame; more is taken as divergence
  double max_rotation_deg = 30.0;    // deg per frame; more is taken as divergence
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(OdometryConfig, levels, finest_level, max_iterations,
                                                max_iterations_finest, alpha_I,
                                                sigma_I, cauchy_c, use_intensity, use_depth, depth_sigma_a,
                                                depth_sigma_b, depth_slope_sigma, min_depth, max_depth,
                                                convergence_eps, occlusion_ratio, min_valid_fraction, max_translation,
                                                max_rotation_deg)
// Throws InputError naming the setting when a value is out of range.
void validate(const OdometryConfig& config);

// One frame prepared for odometry (its pyramid); built once per frame and reused as the next
// frame's reference.
struct OdometryFrame {
  std::vector<PyramidLevel> pyramid;
  const PyramidLevel& level(int l) const { return pyramid.at(l); }
};
OdometryFrame prepareOdometryFrame(const cv::Mat& intensity, const cv::Mat& depth, const CameraIntrinsics& camera,
                                   const OdometryConfig& config);

// Sets every level's target_weight from `weights` (CV_32FC1 in [0, 1], any size; empty clears them).
void setTargetWeights(OdometryFrame& frame, const cv::Mat& weights);

struct OdometryResult {
  bool ok = false;
  std::string message;           // what happened, e.g. why it failed
  SE3 T_cur_ref = SE3::Identity();  // motion: reference-camera points to current-camera points
  int valid_pixels = 0;          // pixels used at the finest level in the last iteration
  int iterations = 0;            // Gauss-Newton iterations, all levels
  double final_cost = 0;         // mean robust cost per valid pixel at the finest level
  Matrix6d hessian = Matrix6d::Zero();  // Gauss-Newton normal matrix at the solution
};

class DenseOdometry {
 public:
  explicit DenseOdometry(const OdometryConfig& config = {});
  // Estimates T_cur_ref. `weights` (optional, CV_32F in [0, 1], any size: resized to each level)
  // scales each reference pixel's terms. `coarsest_level` (-1: levels - 1) is where the
  // coarse-to-fine descent starts; a re-estimate from a close guess needs only the fine levels.
  // Never returns NaN: failures have ok = false and T_cur_ref = the initial guess.
  OdometryResult estimate(const OdometryFrame& ref, const OdometryFrame& cur, const SE3& T_cur_ref_init = SE3::Identity(),
                          const cv::Mat& weights = {}, int coarsest_level = -1) const;
  const OdometryConfig& config() const { return config_; }

 private:
  OdometryConfig config_;
};

// Per-pixel absolute residuals |r_I| ([0,1] units) and |r_D| (m) of the reference frame's
// pixels at pyramid `level` under motion T_cur_ref; NaN where a pixel has no valid warp or lands
// where the other frame's target_weight is below 0.5 (a moving object there, not evidence of
// this pixel's motion).
struct PixelResiduals {
  cv::Mat abs_intensity;  // CV_32F
  cv::Mat abs_depth;      // CV_32F
};
PixelResiduals computePixelResiduals(const OdometryFrame& ref, const OdometryFrame& cur, const SE3& T_cur_ref,
                                     int level, const OdometryConfig& config);

}  // namespace ff
