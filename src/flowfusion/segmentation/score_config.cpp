#include "flowfusion/segmentation/score_config.h"

#include <algorithm>
#include <cmath>

#include "flowfusion/core/error.h"

namespace ff {

void validate(const ScoreConfig& c) {
  if (!(c.alpha_I >= 0 && std::isfinite(c.alpha_I))) throw InputError("scores.alpha_I must be a finite value >= 0");
  if (!(c.alpha_F >= 0 && std::isfinite(c.alpha_F))) throw InputError("scores.alpha_F must be a finite value >= 0");
  if (!(std::isfinite(c.theta_b) && std::isfinite(c.theta_t) && c.theta_t > c.theta_b))
    throw InputError("scores.theta_t must be greater than scores.theta_b (both finite)");
  if (!(c.lambda_G >= 0 && std::isfinite(c.lambda_G))) throw InputError("scores.lambda_G must be a finite value >= 0");
  if (!(c.alpha_M >= 0 && std::isfinite(c.alpha_M)))
    throw InputError("scores.alpha_M must be a finite value >= 0 (0 turns the model term off)");
  if (!(c.model_margin >= 0 && c.model_margin < 1)) throw InputError("scores.model_margin must be in [0, 1)");
  if (!(c.model_motion_delta >= 0 && std::isfinite(c.model_motion_delta)))
    throw InputError("scores.model_motion_delta must be a finite value >= 0");
  if (!(c.model_agreement >= 0 && c.model_agreement <= 1))
    throw InputError("scores.model_agreement must be in [0, 1] (0 turns the map's static evidence off)");
  if (!(c.agreement_margin > 0 && c.agreement_margin < 1)) throw InputError("scores.agreement_margin must be in (0, 1)");
  if (!(c.agreement_intensity > 0 && c.agreement_intensity <= 1))
    throw InputError("scores.agreement_intensity must be in (0, 1] (1 compares depth alone)");
  if (!(c.temporal_prior >= 0 && std::isfinite(c.temporal_prior)))
    throw InputError("scores.temporal_prior must be a finite value >= 0 (0 turns the prior off)");
  if (!(c.body_smoothing >= 0 && std::isfinite(c.body_smoothing)))
    throw InputError("scores.body_smoothing must be a finite value >= 0 (1 = the paper's uniform lambda_G)");
  if (!(c.body_depth_ratio >= 0 && c.body_depth_ratio < 1)) throw InputError("scores.body_depth_ratio must be in [0, 1)");
  if (!(c.group_depth_ratio >= 0 && c.group_depth_ratio < 1)) throw InputError("scores.group_depth_ratio must be in [0, 1)");
  if (!(c.model_memory_s >= 0 && std::isfinite(c.model_memory_s)))
    throw InputError("scores.model_memory_s must be a finite number of seconds >= 0 (0 turns the memory off)");
  if (!(c.hold_seen_moving_s >= 0 && std::isfinite(c.hold_seen_moving_s)))
    throw InputError("scores.hold_seen_moving_s must be a finite number of seconds >= 0 (0 holds nothing)");
  if (!(c.long_baseline_frames >= 0 && c.long_baseline_frames <= 30))
    throw InputError("scores.long_baseline_frames must be in [0, 30] frames (0 turns the long baseline off)");
  if (!(c.long_baseline_max_turn_deg > 0 && c.long_baseline_max_turn_deg <= 180))
    throw InputError("scores.long_baseline_max_turn_deg must be in (0, 180] degrees");
  if (!(c.long_baseline_noise_px >= 0 && c.long_baseline_noise_px <= 100))
    throw InputError("scores.long_baseline_noise_px must be in [0, 100] pixels (0 leaves the chain's residual as it is)");
  if (!(c.model_views >= 0 && c.model_views <= 1000))
    throw InputError("scores.model_views must be in [0, 1000] frames (0 turns the past views off)");
  if (!(c.model_view_every_frames >= 1 && c.model_view_every_frames <= 1000))
    throw InputError("scores.model_view_every_frames must be in [1, 1000] frames");
  if (!(c.model_view_min_age_s >= 0 && std::isfinite(c.model_view_min_age_s)))
    throw InputError("scores.model_view_min_age_s must be a finite number of seconds >= 0");
  if (!(c.target_mover_share >= 0 && c.target_mover_share <= 1))
    throw InputError("scores.target_mover_share must be in [0, 1] (0 turns the rule off)");
  if (!(c.target_mover_margin_px >= 0 && c.target_mover_margin_px <= 16))
    throw InputError("scores.target_mover_margin_px must be in [0, 16] pixels (0 turns the margin off)");
  if (!(c.depth_offset_ms >= 0 && c.depth_offset_ms <= 100))
    throw InputError("scores.depth_offset_ms must be in [0, 100] milliseconds (0: the stamps alone)");
  if (!(c.depth_window_px >= 0 && c.depth_window_px <= 8))
    throw InputError("scores.depth_window_px must be in [0, 8] pixels (0 compares the depth where a pixel lands)");
  if (!(c.flow_error_px >= 0 && std::isfinite(c.flow_error_px)))
    throw InputError("scores.flow_error_px must be a finite number of pixels >= 0 (0 turns the scaling off)");
  if (!(c.flow_consistency_px >= 0 && c.flow_consistency_px <= 100))
    throw InputError("scores.flow_consistency_px must be in [0, 100] pixels (0 turns the check off)");
}

double longBaselineTypicalErrorPx(const ScoreConfig& c, double pair_median_px) {
  if (c.long_baseline_noise_px <= 0) return c.flow_error_px;
  // std::max returns its first argument when the second is NaN.
  return std::min(c.flow_error_px, std::max(c.long_baseline_noise_px, pair_median_px));
}

}  // namespace ff
