#pragma once
// Robust dense RGB-D odometry (FlowFusion Eq. 1-6; Kerl, Sturm, Cremers ICRA 2013).
//
// Source and target as in Open3D's odometry: every source pixel x with depth, the point
// p = pi^-1(x, D_S(x)), is moved by T_target_source (source camera frame to target's) and
// projected into the target T:
//   r_I = I_T(W(x)) - I_S(x)                      (intensity, units of [0, 1] grey)
//   r_D = D_T(W(x)) - [T_target_source p]_z       (depth, metres)
// and  sum_x  v(x) w_T(W(x)) [ C(alpha_I r_I / sigma_I) + C(r_D / sigma_D(x)) ]  is minimised over
// T_target_source by iteratively re-weighted Gauss-Newton, coarse to fine, with the Cauchy penalty
// C(e) = c^2/2 log(1 + (e/c)^2). v(x) in [0, 1] is an optional weight of each source pixel
// (FlowFusion Eq. 16 passes 1 - b) and w_T one of each target pixel (a moving object in the
// target must not attract the background it covered). sigma_D grows with range (Kinect noise model, Nguyen et al. 2012) and with
// the local depth slope, so that depth edges and far surfaces count less. Under yaw (by default),
// D_T is taken with an inverse-depth offset estimated alongside (1 / (1/D_T + offset):
// structured-light depth drifts as the camera turns; OdometryConfig::depth_offset_sigma_per_rad).
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "flowfusion/core/camera.h"
#include "flowfusion/core/image_pyramid.h"
#include "flowfusion/core/se3.h"

namespace ff {

struct OdometryConfig {
  int levels = 4;            // pyramid levels (level l is 2^l times smaller than the input)
  int finest_level = 1;      // finest level aligned; 1 (320x240 for VGA) halves the cost of level 0
  int max_iterations = 6;    // Gauss-Newton iterations per coarse level at most (they are cheap)
  int max_iterations_finest = 2;  // at the finest level, where an iteration costs 4x the one below
  double alpha_I = 0.9;      // weight of the intensity term (paper, Table III)
  double sigma_I = 0.3;      // intensity scale, [0, 1] grey units: r_I is divided by it. Large on
                             // purpose: exposure changes and colour-depth misregistration make
                             // intensity the weaker cue on real frames (docs/tuning.md#odometry)
  double cauchy_c = 1.0;     // Cauchy scale for the normalised residuals (dimensionless)
  bool use_intensity = true;
  bool use_depth = true;
  double depth_sigma_a = 0.0012;  // m, sigma_D(z) = a + b (z - 0.4)^2 (Nguyen et al. 2012)
  double depth_sigma_b = 0.0019;  // 1/m
  double depth_slope_sigma = 1.0; // px of misregistration assumed: adds slope * this to sigma_D
  double min_depth = 0.2;    // m, depths outside [min_depth, max_depth] are ignored
  double max_depth = 6.0;    // m
  double convergence_eps = 1e-6;  // stop a level when the update's norm (m, rad) falls below
  // A source pixel whose warped point lies behind the target's surface by more than this
  // fraction of its depth is hidden in the target (background uncovered by a moving or near
  // object): its intensity and depth there belong to the occluder, so it is left out of the
  // alignment and of computePixelResiduals (0 = keep it; docs/tuning.md#occlusion_ratio).
  double occlusion_ratio = 0.3;
  // Failure detection.
  double min_valid_fraction = 0.05;  // of the finest level's pixels that must take part
  double max_translation = 0.3;      // m per frame; more is taken as divergence
  double max_rotation_deg = 30.0;    // deg per frame; more is taken as divergence
  // Structured-light depth (Kinect v1, TUM fr1) drifts as the camera yaws: on fr1_rpy consecutive
  // frames' inverse depths differ by about 0.025 1/m per radian of yaw, uniformly over the image
  // (a disparity offset, docs/tuning.md#depth_offset_sigma_per_rad), which a 6-DoF fit takes as a
  // forward translation and a shorter yaw. With this > 0 the target's inverse depths get an
  // unknown offset (1/m), estimated with the pose under a zero-mean prior whose standard deviation
  // per valid pixel is this times the yaw of the initial guess (radians): free under fast yaw, held
  // at 0 when the camera barely turns. 0.5 halves the drift of fast-yawing Kinect v1 recordings
  // (fr1_rpy_head150 33.3 -> 16.2 mm without segmentation); 0: the 6-DoF fit.
  double depth_offset_sigma_per_rad = 0.5;
  // Only the part of the estimated offset beyond this (1/m) is taken, and the pose moved to its
  // optimum with the offset held there (to first order): the depth rendered from the map differs
  // from a frame's by about 1e-4 1/m at range, which a free offset turns into forward motion on
  // every keyframe (docs/tuning.md#depth_offset_sigma_per_rad). 0: all of it.
  double depth_offset_dead_zone = 0.0003;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(OdometryConfig, levels, finest_level, max_iterations,
                                                max_iterations_finest, alpha_I,
                                                sigma_I, cauchy_c, use_intensity, use_depth, depth_sigma_a,
                                                depth_sigma_b, depth_slope_sigma, min_depth, max_depth,
                                                convergence_eps, occlusion_ratio, min_valid_fraction, max_translation,
                                                max_rotation_deg, depth_offset_sigma_per_rad, depth_offset_dead_zone)
// Throws InputError naming the setting when a value is out of range.
void validate(const OdometryConfig& config);

// One frame prepared for odometry (its pyramid); built once per frame and reused while it is a
// target.
struct OdometryFrame {
  std::vector<PyramidLevel> pyramid;
  const PyramidLevel& level(int l) const { return pyramid.at(l); }
};
OdometryFrame prepareOdometryFrame(const cv::Mat& intensity, const cv::Mat& depth, const CameraIntrinsics& camera,
                                   const OdometryConfig& config);

struct OdometryResult {
  bool ok = false;
  std::string message;                    // what happened, e.g. why it failed
  SE3 T_target_source = SE3::Identity();  // source-camera points to target-camera points
  int valid_pixels = 0;                   // pixels used at the finest level in the last iteration
  int iterations = 0;                     // Gauss-Newton iterations, all levels
  double final_cost = 0;                  // mean robust cost per valid pixel at the finest level
  double target_depth_offset = 0;         // 1/m added to the target's inverse depths (see OdometryConfig)
  Matrix6d hessian = Matrix6d::Zero();    // Gauss-Newton normal matrix of the pose at the solution (the
                                          // depth offset, where estimated, marginalised)
};

class DenseOdometry {
 public:
  explicit DenseOdometry(const OdometryConfig& config = {});
  // Estimates T_target_source. The weights (optional, CV_32F in [0, 1], any size: resized to each
  // level) scale each source pixel's terms and each target pixel's pull. `coarsest_level` (-1:
  // levels - 1) is where the coarse-to-fine descent starts; a re-estimate from a close guess needs
  // only the fine levels, and starts the depth offset at target_depth_offset_init (a previous
  // estimate's; used only where the guess yaws). Never returns NaN: failures have ok = false and
  // the initial guess.
  OdometryResult estimate(const OdometryFrame& source, const OdometryFrame& target,
                          const SE3& T_target_source_init = SE3::Identity(), const cv::Mat& source_weights = {},
                          const cv::Mat& target_weights = {}, int coarsest_level = -1,
                          double target_depth_offset_init = 0) const;
  const OdometryConfig& config() const { return config_; }

 private:
  // The depth offset prior's weight per valid pixel for a fit starting at T_init (0: none).
  double offsetInformationPerPixel(const SE3& T_init) const;
  // The failure checks on a converged fit, and the result.
  OdometryResult finish(OdometryResult result, const SE3& T, double depth_offset, const Matrix6d& H_last,
                        const OdometryFrame& source, const SE3& T_init) const;

  OdometryConfig config_;
};

// Per-pixel absolute residuals |r_I| ([0,1] units) and |r_D| (m) of the source frame's pixels at
// pyramid `level` under T_target_source; NaN where a pixel has no valid warp, is hidden in the
// target, or lands where target_weights is below 0.5 (a moving object there, not evidence of this
// pixel's motion) or within mover_margin_px pixels (at `level`) of such a place: a mask's outline
// is uncertain by about a pixel, and a surface landing just beside it would be compared with what
// lies behind the mover. With depth_window_px > 0, |r_D| is the smallest depth difference to the
// target's valid depths within that many pixels (at `level`) of where the pixel lands: a depth
// image out of step with its colour image (taken up to 20 ms apart, rolling shutter) puts a thin
// structure's depth edge a few pixels away under fast rotation, where the plain residual compares
// it with the background behind it. target_depth_offset (1/m) is added to the target's inverse
// depths, as the odometry estimated it (OdometryResult::target_depth_offset).
struct PixelResiduals {
  cv::Mat abs_intensity;    // CV_32F
  cv::Mat abs_depth;        // CV_32F
  cv::Mat on_target_mover;  // CV_32F: 1 where the pixel lands in view, not hidden, on such a
                            // moving object of the target (compared with nothing), else 0
};
// The pixels (of a camera with focal length fx_px) by which a static surface's depth edge may lie
// off its colour edge when the depth is taken up to offset_s seconds apart from the colour: the
// image motion of the camera motion T_prev_cur over dt_s seconds (rotation, and translation at
// depth_m metres) scaled to offset_s, rounded, at most max_px; 0 for dt_s <= 0.
int depthOffsetPx(const SE3& T_prev_cur, double dt_s, double fx_px, double depth_m, double offset_s, int max_px);

PixelResiduals computePixelResiduals(const OdometryFrame& source, const OdometryFrame& target,
                                     const SE3& T_target_source, int level, const OdometryConfig& config,
                                     const cv::Mat& target_weights = {}, int mover_margin_px = 0,
                                     int depth_window_px = 0, double target_depth_offset = 0);

}  // namespace ff
