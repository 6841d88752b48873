#pragma once
// The dynamic scores' settings (Eqs. 10-15 and our extensions; each unit of score_evidence.h says
// which it reads). The defaults and the measurements behind them: docs/tuning.md#scores.
#include <nlohmann/json.hpp>

#include "flowfusion/core/config_enum.h"

namespace ff {

// Which of Eq. 10's terms can start a group's motion for model_needs_motion (docs/tuning.md#model_motion_cue).
enum class ModelMotionCue {
  kAnyTerm,  // delta (r_I, r_D and r_F together) above model_motion_delta
  kFlow,     // the flow term alone starts it; delta keeps a group moving that the memory holds
};
FLOWFUSION_CONFIG_ENUM(ModelMotionCue, "scores.model_motion_cue", {ModelMotionCue::kAnyTerm, "any_term"},
                       {ModelMotionCue::kFlow, "flow"})

// What of the flow residual against the camera's motion is its systematic error rather than motion
// (docs/tuning.md#flow_error_field).
enum class FlowErrorField {
  kNone,    // none: r_F as Eq. 9
  kAffine,  // an affine field over the image, fitted robustly to the residual (flowResidualWithoutAffine)
  kAffineParallax,  // ... and the parallax of a translation error (flowResidualWithoutPoseError)
};
FLOWFUSION_CONFIG_ENUM(FlowErrorField, "scores.flow_error_field", {FlowErrorField::kNone, "none"},
                       {FlowErrorField::kAffine, "affine"}, {FlowErrorField::kAffineParallax, "affine_parallax"})

struct ScoreConfig {
  // Weights of Eq. 10. Units: r_I in grey levels (0 to 1), r_D / D_i dimensionless, r_F in pixels
  // of the VGA image. alpha_I is the paper's TUM value (Table III); alpha_F is above its 0.022
  // because our r_F (DIS medium, its error field out, flow_consistency_px) has a lower noise floor
  // on static real clusters than the residual that weight was set for (docs/tuning.md#alpha_f).
  double alpha_I = 0.9;
  double alpha_F = 0.030;
  // Thresholds of g (Eq. 13) on a cluster's delta: below theta_b static, above theta_t dynamic
  // (docs/tuning.md#theta).
  double theta_b = 0.1;
  double theta_t = 0.3;
  // Weight of the smoothness term E_G (Eq. 15); 1 = the paper (docs/tuning.md#lambda_g).
  double lambda_G = 1.0;
  // Factor on lambda_G for the edges between clusters whose mean depths differ by at most
  // body_depth_ratio of the nearer one (our extension; 1 = the paper): the parts of one body (a
  // stance leg, a head beside a moving torso) follow each other more than a body follows the
  // background it stands in front of (docs/tuning.md#body_smoothing).
  double body_smoothing = 2.0;
  double body_depth_ratio = 0.1;  // fraction of the depth
  // Fraction of the depth (our extension; 0 = any): dynamic clusters that touch form one group for
  // model_needs_motion and the motion memory only when their mean depths differ by at most this of
  // the nearer: a black screen's speckles must not take the motion of a dynamic surface 0.3 m
  // behind them (docs/tuning.md#group_depth_ratio).
  double group_depth_ratio = 0.3;
  // Weight of the static-model occlusion term added to Eq. 10 (our extension; 0 = the paper): how
  // far the cluster lies in front of the static map, metres over D_i (docs/tuning.md#alpha_m).
  // It flags a whole object in front of the mapped background, not only its moving edges.
  double alpha_M = 3.0;
  // Depth differences below model_margin * depth are not occlusion (sensor noise, map blur).
  double model_margin = 0.03;
  // A group of clusters that the model term makes dynamic keeps the term only if one of them has
  // motion evidence: a static surface flagged once would otherwise never be fused.
  bool model_needs_motion = true;
  // That motion evidence: Eq. 10's delta above this in one cluster of the group, between theta_b
  // and theta_t (docs/tuning.md#model_motion_delta).
  double model_motion_delta = 0.15;
  // What may show that motion first. Against a target built from the map (a model keyframe) r_D
  // compares the depth with the map's surfaces, so a static surface the map lacks (come into view,
  // or flagged once) has a depth residual and a model occlusion term at once, each confirming the
  // other in every frame (real fr1/rpy): there the flow, an independent cue, starts a group's
  // motion and its memory, and the depth keeps a remembered group moving (a person who sat down
  // stays dynamic). Against a plain frame (ResidualImages::r_D_from_map false) any term starts it.
  ModelMotionCue model_motion_cue = ModelMotionCue::kFlow;
  // Static evidence (our extension): a cluster agreeing with the stable map over a fraction a of
  // its pixels has its motion delta scaled by (1 - model_agreement * a) (docs/tuning.md#agreement).
  double model_agreement = 1.0;
  // Depth differences below agreement_margin * depth agree with the map (tighter than model_margin).
  double agreement_margin = 0.01;
  // Grey levels: a larger intensity difference from the map's front surfel disagrees whatever the
  // depth (a textured face sliding along its own plane); at 1 the depth decides alone.
  double agreement_intensity = 0.2;
  // lambda_T (our extension; 0 = the paper): lambda_T sum_i (b_i - p_i)^2 is added to E(b), p_i the
  // previous scores carried along the motion (docs/tuning.md#temporal_prior).
  double temporal_prior = 0.5;
  // After the odometry was restarted from the flow (consensus), p_i is carried only where the
  // previous scores say dynamic (true; false: none carried after a restart). The restart says the
  // first odometry, weighted by those scores, followed a motion they called static: their static
  // part is the suspect half, while the movers they hold lie where the restarted motion carries
  // them (docs/tuning.md#restart_keeps_movers).
  bool restart_keeps_movers = true;
  // Seconds (our extension; 0 = off): a region that belonged to a moving group of clusters within
  // this time counts as moving for model_needs_motion, so a person who stops (stands, sits) in
  // front of the mapped background stays dynamic while they cover it. Only motion in two frames in
  // a row is remembered, so a static surface flagged once is not, one flagged longer is released
  // after this time (MotionMemory, docs/tuning.md#model_memory_s).
  double model_memory_s = 2.0;
  // Seconds (our extension; 0 = off): a mover once seen moving with a flow of its own off the
  // static map (the clusters pipeline.mask_keep_flow_px and mask_keep_max_agreement keep) is held
  // dynamic where it stands, the hold decaying over this time and let go where the depth shows it
  // walked on or the pixel agrees with the map: a walker who stops, a person standing at the
  // image's border (HeldMovers, docs/tuning.md#hold_seen_moving_s).
  double hold_seen_moving_s = 1.0;
  // Past views (our extension; 0 = off): the model term is withheld at a pixel where one of the
  // last model_views scored frames (one of every model_view_every_frames) at least
  // model_view_min_age_s old saw a static surface at its point and none saw through it: a surface
  // come back into view, or uncovered by parallax, in front of surfels fused from other viewpoints
  // (PastViews, docs/tuning.md#model_views). The age keeps out the recent frames that missed a
  // mover still standing where they saw it. 60 of every 5th frame: 10 s at 30 Hz, 23 MB at 320x240.
  int model_views = 60;
  int model_view_every_frames = 5;
  double model_view_min_age_s = 2.0;
  // Fraction (our extension; 0 = off): a cluster with at least this share of its pixels landing on
  // the target's own movers (residuals.on_target_mover) was compared with nothing there, and a
  // small flow residual alone (the inside of a slow or turning mover) is no evidence that it
  // stands still: its neighbours and its carried score decide, unless its delta reaches theta_t
  // or it agrees with the map (docs/tuning.md#target_mover_share).
  double target_mover_share = 0.5;
  // Pixels (at the segmentation level; our extension, 0 = off): a pixel landing this close to the
  // target's movers counts as landing on them (computePixelResiduals' mover_margin_px). A static
  // object scored dynamic in a keyframe keeps its own depth there; its edge, landing just outside
  // that mask, would show the depth of the map behind it as motion and keep it dynamic
  // (docs/tuning.md#target_mover_margin_px).
  int target_mover_margin_px = 1;
  // Milliseconds (our extension): how far apart the depth may be taken from the colour beyond
  // what their stamps say (RgbdFrame::depth_timestamp; a rolling shutter, stamps of arrival). Real
  // depth is out of step with colour under fast rotation (fr1/rpy: stamps up to 11 ms apart; a thin
  // desk edge 2 m away lands a few pixels off over the far background, a metre of depth residual
  // that the memory then keeps), so r_D is the smallest depth difference within the pixels the
  // camera's image motion covers in that time (depthOffsetPx), at most depth_window_px at the
  // segmentation level (0 = off; docs/tuning.md#depth_offset_ms).
  double depth_offset_ms = 2.0;
  int depth_window_px = 4;
  // Pixels of the VGA image (our extension; 0 = off): when the median flow residual over the frame
  // exceeds this, the flow failed on the frame as a whole (real motion blur, a large rotation the
  // flow did not follow), and r_F is scaled by this over the median (relativeToFrameError), so only
  // what stands out from the frame's own error counts (docs/tuning.md#flow_error_px).
  double flow_error_px = 2.0;
  // Long baseline (our extension; 0 = off): r_F is also taken against the frame this many scored
  // frames back, along the frames' own flows chained, and the larger of the two counts. A person
  // walking with the camera's pan moves 1-3 px a frame against the room, as little as a frame's own
  // flow error, but that adds up over frames. Only while the camera turned at most
  // long_baseline_max_turn_deg since that frame (a fast turn blurs the frames apart and the chained
  // flow fails), and not where that frame saw something nearer (hiddenIn, within model_margin)
  // (docs/tuning.md#long_baseline_frames).
  int long_baseline_frames = 4;
  double long_baseline_max_turn_deg = 3.0;
  // Pixels of the VGA image (our extension; 0 = off): the chain carries every step's error, and
  // its residual's median is about twice a frame pair's on real and synthetic frames alike. Where
  // it is above the larger of this and the pair's own median, the chain's residual is scaled down
  // to that (relativeToFrameError): alpha_F was set for a pair's residual on static real frames (median
  // 0.45-0.49 px, tests/segmentation/test_scores_fr1.cpp), so the chain's noise counts no more than
  // that. A chain as quiet as that already (synthetic frames: 0.3 px) is left as it is, and with
  // it the slow movers it finds (docs/tuning.md#long_baseline_noise_px).
  double long_baseline_noise_px = 0.5;
  // Our extension: a small error of the camera's rotation, the rolling shutter and the colour-depth
  // offset under rotation shift the whole static background by a smooth field of a few pixels,
  // which r_F counts as motion everywhere; kAffine takes a robust affine fit of it out of r_F
  // against the camera's motion. On blurred frames the odometry's translation can be 1-2 cm off,
  // which moves near surfaces more than far ones; kAffineParallax fits that parallax too, away
  // from the pixels the scores already hold for movers (docs/tuning.md#flow_error_field).
  FlowErrorField flow_error_field = FlowErrorField::kAffineParallax;
  // Pixels of the input image (our extension; 0 = off): r_F is no evidence where the flow back from
  // the previous image does not bring the pixel back within this plus 5 % of its flow
  // (inconsistentFlow): there the flow matched nothing reliable (blur, occlusion, no texture). A
  // second flow per frame (docs/tuning.md#flow_consistency_px).
  double flow_consistency_px = 2.0;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(ScoreConfig, alpha_I, alpha_F, theta_b, theta_t, lambda_G,
                                                body_smoothing, body_depth_ratio, group_depth_ratio, alpha_M, model_margin,
                                                model_needs_motion, model_motion_delta, model_motion_cue, model_agreement,
                                                agreement_margin, agreement_intensity, temporal_prior, restart_keeps_movers,
                                                model_memory_s, hold_seen_moving_s,
                                                model_views, model_view_every_frames, model_view_min_age_s,
                                                target_mover_share, target_mover_margin_px, depth_offset_ms, depth_window_px,
                                                flow_error_px, long_baseline_frames, long_baseline_max_turn_deg, long_baseline_noise_px,
                                                flow_error_field, flow_consistency_px)
// Throws InputError naming the first bad setting.
void validate(const ScoreConfig& config);

// The typical error (px) the long baseline's residual is scaled to (relativeToFrameError):
// flow_error_px, and with long_baseline_noise_px the smaller of that and the larger of the setting
// and the frame pair's median residual; a NaN median (no finite pair residual) keeps the setting.
double longBaselineTypicalErrorPx(const ScoreConfig& config, double pair_median_px);

}  // namespace ff
