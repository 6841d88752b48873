#pragma once
// The per-frame FlowFusion loop (paper Fig. 1, Sections III-A to III-C).
//
// Frames: the paper's reference frame A, whose pixels carry clusters, residuals and scores, is
// here the CURRENT frame, and the frame it is aligned to (the paper's B) is the last keyframe (by
// default with the static map's depth predicted at its pose), the previous frame, or the map's
// prediction at the previous pose (PipelineOptions::tracking). The mathematics is the paper's with time
// reversed; in exchange every frame's dynamic mask, fusion weights and odometry weights live in
// its own pixels, and the map prediction (static only by construction) is the target, never the
// weighted side. Optical flow therefore runs from the current to the previous image.
//
// Per frame:  optical flow -> odometry (Eq. 1, weighted by the previous frame's scores carried
// over when available; restarted from the flow's rigid consensus when that explains clearly more
// of the flow, flow/flow_motion.h) -> [flow residual (Eq. 8-9), clusters, scores (Eq. 10-15, with the static map's
// occlusion and agreement terms of ScoreConfig), weighted odometry (Eq. 16)] repeated until the
// motion settles -> static map fusion with weights 1 - b. The frame then becomes the next
// frame's target (previous frame or keyframe) with its static weights 1 - b as target weights.
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "flowfusion/core/camera.h"
#include "flowfusion/core/rgbd_frame.h"
#include "flowfusion/eval/bench_utils.h"
#include "flowfusion/flow/flow_motion.h"
#include "flowfusion/flow/optical_flow.h"
#include "flowfusion/fusion/static_map.h"
#include "flowfusion/io/trajectory_io.h"
#include "flowfusion/odometry/dense_odometry.h"
#include "flowfusion/segmentation/clustering.h"
#include "flowfusion/segmentation/dynamic_score.h"

namespace ff {

struct PipelineOptions {
  // "frame_to_frame": align to the previous frame; "frame_to_keyframe": align to the last
  // keyframe, replaced once the camera moved keyframe_translation or keyframe_rotation_deg from
  // it (drift grows per keyframe, not per frame); "frame_to_model": align to the static map's
  // depth predicted at the previous pose (falls back to the previous frame where the map is thin).
  std::string tracking = "frame_to_keyframe";
  double keyframe_translation = 0.05;   // m
  double keyframe_rotation_deg = 5.0;   // deg
  // A new keyframe takes its depth from the static map predicted at its pose (StaticMap::predictDepth;
  // model_min_valid_fraction applies; its own image stays the photometric target, and its dynamic
  // pixels keep their depth): frame-to-model tracking whose prediction is rendered once per
  // keyframe (about one frame in five on fr1/xyz) instead of every frame.
  // Measured against plain keyframes (flowfusion run, default otherwise; ATE mm): static fr1 14.8
  // -> 12.9 (frame to frame 13.7, frame to model 13.5), augmented fr1 16.9 -> 14.5 (frame to frame
  // 33.1), synth seeds 1-6 (150 frames) 6.0, 3.2, 3.0, 2.9, 2.3, 6.6 -> 3.9, 3.4, 5.3, 1.6, 1.7,
  // 2.3 (mean 4.0 -> 3.0), their static twins 6.0, 0.6, 0.5, 2.5, 1.2, 4.0 -> 4.2, 2.6, 1.7, 1.3,
  // 1.2, 0.7: the map's averaged depth helps most on real sensor noise; on the exact synthetic
  // geometry of seeds 2 and 3 the map's own small errors (its depth 1-2 mm off the frames'
  // median) outweigh it. Mean IoU about unchanged (augmented fr1 0.643 -> 0.660, synth mean
  // 0.799 -> 0.793). Keyframes every 3 cm / 3 deg or 10 cm / 10 deg measured no better; keeping
  // the frame's depth wherever it differs from the map's by more than fusion.association_distance_m
  // (instead of at its dynamic pixels only) was worse on synth seeds 1, 3, 6 (4.8, 8.1, 2.8 mm).
  bool model_keyframes = true;
  bool segmentation = true;          // false: the plain robust odometry (--no-segmentation)
  int max_iterations = 8;            // segmentation <-> odometry rounds at most (paper, Table III)
  double converged_translation = 0.0005;  // m: the loop stops when a round moves the pose less
  double converged_rotation_deg = 0.05;   // deg: ... and rotates it less than this
  // Pyramid level the weighted re-estimates of the loop start from (-1: the coarsest). They start
  // at the last round's pose, a fraction of a pixel from the answer at the finer levels, so the
  // coarse levels only cost time.
  int refine_coarsest_level = 1;
  int refine_iterations = 1;         // Gauss-Newton iterations per level of each re-estimate
  int segmentation_level = 1;        // pyramid level of clusters and residuals (1 = half size)
  float mask_threshold = 0.5f;       // pixels with b above it are written as dynamic
  // Weights of the first odometry of a frame come from the previous frame's scores, so a moving
  // object seen before does not pull the initial estimate (off: the paper's unweighted Eq. 1).
  bool carry_scores = true;
  bool fusion = true;                // build the static map (needed for frame_to_model)
  // Fuse every n-th frame. 2 halves the fusion time, and a surface needs twice as many frames
  // (4) to become stable, so a moving object missed for a frame or two is less often taken as
  // background. Measured against 1 (flowfusion run; ATE mm / pooled IoU): fr1 augmented 16.0 / 0.62
  // -> 16.4 / 0.69, static fr1 14.9 -> 15.8 mm, synth seeds 1, 2, 4, 5, 6 (150 frames) 6.3 / .96,
  // 2.6 / .84, 2.7 / .88, 2.0 / .76, 6.0 / .58 -> 5.9 / .96, 3.2 / .83, 2.9 / .86, 2.0 / .73,
  // 6.4 / .61; the augmented map's points farther than 3 cm from the static fr1 map 2.9 % -> 0.8 %
  // (flowfusion eval map).
  int fusion_every = 2;
  // Start each frame's odometry from the previous frame's motion (else from no motion).
  bool constant_velocity = true;
  // Report each pose at the colour image's time, moved from the depth image's time along the
  // last motion (TUM's colour and depth are up to 20 ms apart).
  bool shift_to_colour_time = true;
  double model_min_valid_fraction = 0.5;  // of the current frame's depth pixels the prediction
                                          // must cover for frame_to_model to be used
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(PipelineOptions, tracking, keyframe_translation,
                                                keyframe_rotation_deg, model_keyframes, segmentation, max_iterations,
                                                converged_translation, converged_rotation_deg, refine_coarsest_level,
                                                refine_iterations, segmentation_level,
                                                mask_threshold, carry_scores, fusion, fusion_every, constant_velocity,
                                                shift_to_colour_time,
                                                model_min_valid_fraction)

struct SystemConfig {
  PipelineOptions pipeline;
  OdometryConfig odometry;
  FlowConfig flow;
  ConsensusConfig consensus;
  ClusteringConfig clustering;
  ScoreConfig scores;
  FusionConfig fusion;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(SystemConfig, pipeline, odometry, flow, consensus, clustering, scores,
                                                fusion)
// Throws InputError naming the first bad setting.
void validate(const SystemConfig& config);

struct FrameResult {
  double timestamp = 0;
  SE3 T_world_cam = SE3::Identity();
  bool tracking_ok = true;
  std::string message;          // what the tracker did when it did not simply succeed
  bool used_model = false;      // aligned to the map prediction (frame_to_model or a model keyframe)
  bool restarted_from_flow = false;  // the odometry was restarted from the flow's rigid consensus
  int iterations = 0;           // segmentation rounds
  cv::Mat dynamic_mask;         // CV_8U, input size, 255 = dynamic, in this frame's pixels
  cv::Mat scores;               // CV_32F b per pixel at the segmentation level (empty when off)
};

class FlowFusionSystem {
 public:
  FlowFusionSystem(const SystemConfig& config, const CameraIntrinsics& camera,
                   const SE3& T_world_first = SE3::Identity());
  ~FlowFusionSystem();

  // Processes the next frame (in time order) and returns its pose and mask. Stage times are added
  // to timings() under "odometry", "flow", "consensus", "clustering", "scores", "prediction", "fusion".
  FrameResult process(const RgbdFrame& frame);

  const Trajectory& trajectory() const { return trajectory_; }
  const StaticMap* map() const { return map_.get(); }
  eval::Timings& timings() { return timings_; }
  const SystemConfig& config() const { return config_; }
  int trackingFailures() const { return failures_; }
  int flowRestarts() const { return flow_restarts_; }

 private:
  struct Previous;
  // The map's depth predicted at source's pose with source's image as the photometric target, as
  // an odometry target (source's own depth at the `keep` pixels and where the map has none); none
  // when the prediction covers less than model_min_valid_fraction of source's depth pixels at the
  // odometry's finest level.
  std::optional<OdometryFrame> modelTarget(const Previous& source, const cv::Mat& keep = {}) const;
  SystemConfig config_;
  CameraIntrinsics camera_;
  DenseOdometry odometry_;
  DenseOdometry refine_odometry_;  // the loop's re-estimates (refine_iterations per level)
  std::unique_ptr<OpticalFlow> flow_;
  std::unique_ptr<Clusterer> clusterer_;
  std::unique_ptr<StaticMap> map_;
  std::unique_ptr<Previous> prev_;
  std::unique_ptr<Previous> keyframe_;
  SE3 T_world_first_;
  SE3 T_prev_cur_velocity_ = SE3::Identity();  // last frame-to-frame motion, the next guess
  double velocity_dt_ = 0;                      // s, the time that motion took
  Trajectory trajectory_;
  eval::Timings timings_;
  int failures_ = 0;
  int flow_restarts_ = 0;
};

}  // namespace ff
