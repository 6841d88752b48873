#pragma once
// The whole system's configuration: one section per stage (each documented in its stage's
// header) and the pipeline's own options. A run writes it as config.json, a valid --config file.
#include <nlohmann/json.hpp>

#include "flowfusion/core/config_enum.h"
#include "flowfusion/flow/flow_motion.h"
#include "flowfusion/flow/optical_flow.h"
#include "flowfusion/fusion/static_map.h"
#include "flowfusion/odometry/dense_odometry.h"
#include "flowfusion/segmentation/clustering.h"
#include "flowfusion/segmentation/dynamic_score.h"
#include "flowfusion/slam/slam_config.h"

namespace ff {

// What each frame is aligned to (pipeline/tracking_target.h).
enum class TrackingMode {
  FrameToFrame,     // the previous frame
  FrameToKeyframe,  // the last keyframe, replaced once the camera moved far enough from it
  FrameToModel,     // the static map's depth predicted at the previous pose (else the previous frame)
};
FLOWFUSION_CONFIG_ENUM(TrackingMode, "pipeline.tracking", {TrackingMode::FrameToFrame, "frame_to_frame"},
                       {TrackingMode::FrameToKeyframe, "frame_to_keyframe"},
                       {TrackingMode::FrameToModel, "frame_to_model"})

struct PipelineOptions {
  TrackingMode tracking = TrackingMode::FrameToKeyframe;
  double keyframe_translation = 0.05;   // m the camera moves from a keyframe before a new one
  double keyframe_rotation_deg = 5.0;   // deg the camera turns from a keyframe before a new one
  // A new keyframe takes its depth from the static map predicted at its pose (its own image stays
  // the photometric target, its dynamic pixels keep their depth): frame-to-model tracking with one
  // rendering per keyframe (docs/tuning.md#model_keyframes).
  bool model_keyframes = true;
  bool segmentation = true;          // false: the plain robust odometry (--no-segmentation)
  int max_iterations = 8;            // segmentation <-> odometry rounds at most (paper, Table III)
  double converged_translation = 0.0005;  // m: the loop stops when a round moves the pose less
  double converged_rotation_deg = 0.05;   // deg: ... and rotates it less than this
  // Pyramid level the loop's weighted re-estimates start from (-1: the coarsest); they start a
  // fraction of a pixel from the answer, so the coarse levels only cost time.
  int refine_coarsest_level = 1;
  int refine_iterations = 1;         // Gauss-Newton iterations per level of each re-estimate
  int segmentation_level = 1;        // pyramid level of clusters and residuals (1 = half size)
  float mask_threshold = 0.5f;       // pixels with b above it are written as dynamic
  // A region without depth is written as dynamic when at least this share of the pixels with depth
  // around it is (fillDepthHoles: a mover nearer than the sensor's range; 0: never).
  double mask_hole_share = 0.8;
  // ... and a pixel without depth is, beside a mover, where its optical flow differs by more than
  // this (pixels, after scores.flow_error_px's scaling) from the camera's motion at every depth
  // the surfaces around it and the stable map offer (movingHoles: a box nearer than the range; 0: never).
  double mask_hole_flow_px = 4.0;
  // ... in the sensor's band too (SensorBand: the image's edges where a registered depth image has
  // no depth for anything): a mover's part there is written where its flow moves beside the written
  // mover and its colour is likelier the mover's than the room's around it (the flow beside a mover
  // at the edge spills over the room there; clearBandHolesOfWorldColour, docs/tuning.md#mask_band_holes).
  bool mask_band_holes = true;
  // ... and, with it, every band pixel within this many rows and columns of the written mask, whatever
  // its flow, under the same colour test (bandBesideMovers: a person standing at the image's edge
  // barely moves against the room; 0: only the moving ones; docs/tuning.md#mask_band_reach_px).
  int mask_band_reach_px = 30;
  // Pixels whose depth and grey level coincide with the stable static map (scores.agreement_margin,
  // agreement_intensity; none while scores.model_agreement is 0) are written as static
  // (clearMapAgreement: the background beside a mover that its clusters straddle or hold).
  bool mask_map_agreement = true;
  // Share of the image (0: keep all): a dynamic region smaller than it that touches no image border
  // is written as static (dropSmallInteriorRegions: a static cluster's own residual on real frames).
  double mask_min_region = 0.02;
  // Pixels of the input image (0: drop them all): such a small region stays when most of it lies on
  // clusters seen moving with a flow residual of at least this and less than
  // mask_keep_max_agreement of their pixels on the stable map (seenMovingClusters: a box 2 m away).
  double mask_keep_flow_px = 4.0;
  double mask_keep_max_agreement = 0.1;
  // Pixels of the input image (0: off): within this radius of the written mask's edge a pixel
  // joins the side whose depth it is nearer across a depth step, one without depth the side whose
  // colour it is nearer (refineMaskEdges: the scores' half-size pixels, the sensor's shadow).
  int mask_edge_px = 2;
  // Keep each scored frame's per-cluster evidence (FrameResult::clusters; `run --cluster-log`
  // writes it): why a region is marked or not. One row per cluster.
  bool cluster_log = false;
  // The first odometry of a frame is weighted by the previous frame's scores carried over, so a
  // moving object seen before does not pull it (false: the paper's unweighted Eq. 1).
  bool carry_scores = true;
  bool fusion = true;                // build the static map (needed for frame_to_model)
  // Fuse every n-th frame: half the fusion time at 2, and a moving object missed for a frame or
  // two is less often taken as background (docs/tuning.md#fusion_every).
  int fusion_every = 2;
  // Start each frame's odometry from the previous frame's motion (else from no motion).
  bool constant_velocity = true;
  // Report each pose at the colour image's time, moved from the depth image's time along the
  // last motion (TUM's colour and depth are up to 20 ms apart).
  bool shift_to_colour_time = true;
  // Fraction of the frame's depth pixels a map prediction must cover to serve as a target.
  double model_min_valid_fraction = 0.5;
  // ms a frame may take (0: no budget). Past it, the frame skips its optional parts, so a machine
  // behind a live camera catches up (run --realtime): segmentation rounds after the first, and its
  // fusion, which the next frame then does (never more than 2 x fusion_every frames unfused).
  // Results then depend on the machine's speed; 0 keeps them reproducible (docs/tuning.md#budget_ms).
  double budget_ms = 0;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(PipelineOptions, tracking, keyframe_translation, keyframe_rotation_deg,
                                                model_keyframes, segmentation, max_iterations, converged_translation,
                                                converged_rotation_deg, refine_coarsest_level, refine_iterations,
                                                segmentation_level, mask_threshold, mask_hole_share, mask_hole_flow_px,
                                                mask_band_holes, mask_band_reach_px, mask_map_agreement,
                                                mask_min_region, mask_keep_flow_px, mask_keep_max_agreement,
                                                mask_edge_px, cluster_log, carry_scores, fusion, fusion_every,
                                                constant_velocity, shift_to_colour_time, model_min_valid_fraction,
                                                budget_ms)

struct SystemConfig {
  PipelineOptions pipeline;
  OdometryConfig odometry;
  FlowConfig flow;
  ConsensusConfig consensus;
  ClusteringConfig clustering;
  ScoreConfig scores;
  FusionConfig fusion;
  SlamConfig slam;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(SystemConfig, pipeline, odometry, flow, consensus, clustering, scores,
                                                fusion, slam)

// Checks every section (each stage's validate()) and the pipeline's options against them.
// Throws InputError naming the first bad setting.
void validate(const SystemConfig& config);

// The frame budget a live run starts from (run --realtime, the ROS node), ms: nine tenths of a
// 30 Hz camera's frame interval. A live run's results depend on the machine anyway (what it
// drops); with the budget a late frame skips its optional parts instead of making the next ones
// wait (docs/tuning.md#budget_ms).
constexpr double kLiveBudgetMs = 30;
// The defaults of a live run: SystemConfig{} with pipeline.budget_ms = kLiveBudgetMs and the DIS
// fast preset (two medium flows a frame cost 16 ms more than two fast ones, which a 30 Hz camera
// on two cores cannot spare; docs/performance.md). A configuration file or --set still decides
// (pipeline.budget_ms=0: no budget).
SystemConfig liveDefaults();

}  // namespace ff
