#include "flowfusion/pipeline/system_config.h"

#include <cmath>

#include "flowfusion/core/error.h"

namespace ff {

namespace {

void validate(const PipelineOptions& p, const OdometryConfig& odometry) {
  const auto positive = [](double v) { return v > 0 && std::isfinite(v); };
  if (p.tracking == TrackingMode::FrameToModel && !p.fusion)
    throw InputError("pipeline.tracking frame_to_model needs pipeline.fusion = true (the map is the model)");
  if (!positive(p.keyframe_translation)) throw InputError("pipeline.keyframe_translation must be > 0 (metres)");
  if (!positive(p.keyframe_rotation_deg)) throw InputError("pipeline.keyframe_rotation_deg must be > 0 (degrees)");
  if (p.max_iterations < 1 || p.max_iterations > 100) throw InputError("pipeline.max_iterations must be 1 to 100");
  if (!positive(p.converged_translation)) throw InputError("pipeline.converged_translation must be > 0 (metres)");
  if (!positive(p.converged_rotation_deg)) throw InputError("pipeline.converged_rotation_deg must be > 0 (degrees)");
  if (p.refine_coarsest_level < -1 || p.refine_coarsest_level >= odometry.levels)
    throw InputError("pipeline.refine_coarsest_level must be -1 (the coarsest) or in [0, odometry.levels)");
  if (p.refine_iterations < 1 || p.refine_iterations > 100)
    throw InputError("pipeline.refine_iterations must be 1 to 100");
  if (p.segmentation_level < 0 || p.segmentation_level >= odometry.levels)
    throw InputError("pipeline.segmentation_level must be in [0, odometry.levels)");
  if (!(p.mask_threshold > 0 && p.mask_threshold < 1)) throw InputError("pipeline.mask_threshold must be in (0, 1)");
  if (!(p.mask_hole_share >= 0 && p.mask_hole_share <= 1))
    throw InputError("pipeline.mask_hole_share must be 0 (never) to 1 (a share of the hole's neighbours)");
  if (!(p.mask_hole_flow_px >= 0 && std::isfinite(p.mask_hole_flow_px)))
    throw InputError("pipeline.mask_hole_flow_px must be a finite number of pixels >= 0 (0: never)");
  if (p.mask_band_reach_px < 0 || p.mask_band_reach_px > 200)
    throw InputError("pipeline.mask_band_reach_px must be 0 (only the band's moving holes) to 200 pixels");
  if (p.mask_edge_px < 0 || p.mask_edge_px > 16) throw InputError("pipeline.mask_edge_px must be 0 (off) to 16");
  if (!(p.mask_min_region >= 0 && p.mask_min_region < 1))
    throw InputError("pipeline.mask_min_region must be 0 (keep every region) or a share of the image below 1");
  if (!(p.mask_keep_flow_px >= 0 && p.mask_keep_flow_px <= 1e4))
    throw InputError("pipeline.mask_keep_flow_px must be 0 (keep no small region) to 1e4 pixels");
  if (!(p.mask_keep_max_agreement > 0 && p.mask_keep_max_agreement <= 1))
    throw InputError("pipeline.mask_keep_max_agreement must be in (0, 1] (a share of a cluster's pixels)");
  if (p.fusion_every < 1 || p.fusion_every > 1000) throw InputError("pipeline.fusion_every must be 1 to 1000");
  if (!(p.model_min_valid_fraction >= 0 && p.model_min_valid_fraction <= 1))
    throw InputError("pipeline.model_min_valid_fraction must be in [0, 1]");
  if (!(p.budget_ms >= 0 && p.budget_ms <= 1e6))
    throw InputError("pipeline.budget_ms must be 0 (no budget) to 1e6 (milliseconds per frame)");
}

}  // namespace

void validate(const SystemConfig& c) {
  validate(c.odometry);
  validate(c.pipeline, c.odometry);
  validate(c.flow);
  validate(c.consensus);
  validate(c.clustering);
  validate(c.scores);
  validate(c.fusion);
  validate(c.slam, c.odometry.levels);
}

SystemConfig liveDefaults() {
  SystemConfig c;
  c.pipeline.budget_ms = kLiveBudgetMs;
  c.flow.dis_preset = DisPreset::Fast;
  return c;
}

}  // namespace ff
