#include "flowfusion/slam/slam_config.h"

#include <cmath>
#include <string>

#include "flowfusion/core/error.h"

namespace ff {

void validate(const SlamConfig& c, int odometry_levels) {
  const auto positive = [](double v) { return v > 0 && std::isfinite(v); };
  const auto fraction = [](double v) { return v >= 0 && v <= 1; };
  if (!positive(c.keyframe_translation_m)) throw InputError("slam.keyframe_translation_m must be > 0 (metres)");
  if (!positive(c.keyframe_rotation_deg)) throw InputError("slam.keyframe_rotation_deg must be > 0 (degrees)");
  if (c.keyframe_level < 0 || c.keyframe_level >= odometry_levels)
    throw InputError("slam.keyframe_level must be in [0, odometry.levels)");
  if (c.fern_count < 16 || c.fern_count > 10000) throw InputError("slam.fern_count must be 16 to 10000");
  if (c.fern_image_width < 16 || c.fern_image_width > 640) throw InputError("slam.fern_image_width must be 16 to 640");
  if (!fraction(c.min_similarity)) throw InputError("slam.min_similarity must be in [0, 1]");
  if (c.candidates < 1 || c.candidates > 20) throw InputError("slam.candidates must be 1 to 20");
  if (c.min_keyframe_gap < 1) throw InputError("slam.min_keyframe_gap must be >= 1 (keyframes)");
  if (!fraction(c.min_inlier_fraction)) throw InputError("slam.min_inlier_fraction must be in [0, 1]");
  if (!positive(c.inlier_depth_m)) throw InputError("slam.inlier_depth_m must be > 0 (metres)");
  if (!positive(c.inlier_intensity)) throw InputError("slam.inlier_intensity must be > 0 ([0, 1] grey)");
  if (!positive(c.max_correction_m)) throw InputError("slam.max_correction_m must be > 0 (metres)");
  if (!positive(c.max_correction_deg)) throw InputError("slam.max_correction_deg must be > 0 (degrees)");
  if (!(c.min_correction_m >= 0)) throw InputError("slam.min_correction_m must be >= 0 (metres)");
  if (!(c.min_correction_deg >= 0)) throw InputError("slam.min_correction_deg must be >= 0 (degrees)");
  if (!positive(c.odometry_sigma_m) || !positive(c.loop_sigma_m))
    throw InputError("slam.odometry_sigma_m and slam.loop_sigma_m must be > 0 (metres)");
  if (!positive(c.odometry_sigma_deg) || !positive(c.loop_sigma_deg))
    throw InputError("slam.odometry_sigma_deg and slam.loop_sigma_deg must be > 0 (degrees)");
  if (!(c.odometry_loss_scale >= 0))
    throw InputError("slam.odometry_loss_scale must be >= 0 (standard deviations; 0: no robust loss)");
  if (!positive(c.loop_loss_scale)) throw InputError("slam.loop_loss_scale must be > 0 (standard deviations)");
  if (c.apply_after_frames < 1 || c.apply_after_frames > 1000)
    throw InputError("slam.apply_after_frames must be 1 to 1000");
}

bool loopClosureAvailable() {
#ifdef FLOWFUSION_HAVE_CERES
  return true;
#else
  return false;
#endif
}

}  // namespace ff
