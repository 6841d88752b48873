#pragma once
// The segmentation loop of one frame (paper Fig. 1, Sections III-B and III-C): optical flow from
// the current to the previous image; a restart of the odometry from the flow's rigid consensus
// when that explains clearly more of the flow (flow/flow_motion.h); then clusters, residuals
// r_I, r_D, r_F (Eq. 8-9) and the static map's occlusion and agreement evidence, dynamic scores
// (Eq. 10-15) and the odometry re-estimated with weights 1 - b (Eq. 16), repeated until the
// motion settles.
//
// Frames: the paper's frame A, whose pixels carry clusters and scores, is the CURRENT frame (the
// odometry's source); the target is the tracking target (previous frame, keyframe or the map's
// prediction), so each frame's mask and weights live in its own pixels.
#include <chrono>
#include <deque>
#include <memory>

#include "flowfusion/core/timings.h"
#include "flowfusion/flow/flow_motion.h"
#include "flowfusion/flow/optical_flow.h"
#include "flowfusion/pipeline/tracking_target.h"
#include "flowfusion/segmentation/cluster_log.h"
#include "flowfusion/segmentation/clustering.h"
#include "flowfusion/segmentation/depth_holes.h"
#include "flowfusion/segmentation/held_movers.h"
#include "flowfusion/segmentation/motion_memory.h"
#include "flowfusion/segmentation/past_views.h"

namespace ff {

// The motion of the current frame against its target and the scores that go with it.
struct MotionEstimate {
  OdometryResult odometry;   // the last successful full estimate (or the failed first one)
  SE3 T_target_cur;          // current-camera points into the target camera
  double target_depth_offset = 0;  // 1/m, the target's inverse-depth offset estimated with T_target_cur
  cv::Mat scores;            // b per pixel at the segmentation level; empty when none
  // 255 where the pixel coincides with the stable static map (modelAgreement) at the segmentation
  // level; empty without a map or a scored frame
  cv::Mat map_agreement;
  // 255 on the clusters seen moving with a flow of their own (seenMovingClusters), whose small
  // regions the written mask keeps, at the segmentation level; empty when none or the rule is off
  cv::Mat seen_moving;
  // 255 on the pixels without depth whose flow no static surface around them explains (movingHoles,
  // pipeline.mask_hole_flow_px), at the segmentation level; the written mask takes those beside its
  // movers. Empty when none
  cv::Mat moving_holes;
  // 255 on the sensor's band (the run's median width, SensorBandMedian) at the segmentation level:
  // no hole there is tested for its own motion (unless pipeline.mask_band_holes), and the written
  // mask's hole fill leaves it as the scores left it; empty before a scored frame
  cv::Mat sensor_band;
  cv::Mat flow_mover;        // 1 on the flow's own mover (FlowMotionSplit) at the segmentation level; empty when none
  bool flow_mover_holds = false;  // the flow's mover stays dynamic through the rounds (at the start)
  bool restarted_from_flow = false;
  int rounds = 0;            // score <-> odometry rounds run
  ClusterLog cluster_log;    // the last round's per-cluster evidence (pipeline.cluster_log); else empty
};

struct SegmentationInput {
  const RgbdFrame& frame;
  const OdometryFrame& cur;
  const TrackedFrame& previous;
  const TrackingTarget& target;
  SE3 T_target_prev;
  const StaticMap* map;  // null without fusion
  // Past it (pipeline.budget_ms), no round after the first starts; the default never comes.
  std::chrono::steady_clock::time_point deadline = std::chrono::steady_clock::time_point::max();
};

// What the loop needs of the current frame that depends neither on the odometry nor on the map:
// the dense flow from the current image to the previous one and the current frame's clusters.
struct FrameCues {
  FlowField flow;
  FlowField flow_back;    // from the previous image to the current one; empty when the check is off
  ClusterGraph graph;     // at the segmentation level
  double flow_ms = 0;     // wall time of each, for Timings ("flow", "clustering")
  double clustering_ms = 0;
};

class SegmentationLoop {
 public:
  SegmentationLoop(const SystemConfig& config, const CameraIntrinsics& camera);
  // The frame's cues; runs on another thread while the first odometry does (it reads only its
  // arguments and the flow and clustering backends, which no other call uses).
  FrameCues computeCues(const RgbdFrame& frame, const OdometryFrame& cur, const RgbdFrame& previous);
  // Refines `estimate`, which holds the first odometry and the carried scores, with the frame's cues.
  void run(const SegmentationInput& in, const FrameCues& cues, MotionEstimate& estimate, Timings& timings);

 private:
  // r_F (Eq. 9) at the segmentation level under T_prev_cur, in pixels of the input image;
  // `seg_flow` is the flow resampled to the segmentation level (resizeFlow). Against the camera's
  // own motion (camera_motion) without the systematic field scores.flow_error_field names, fitted
  // away from `movers` (CV_8U at the segmentation level, non-zero; optional).
  cv::Mat flowResidualAt(const FlowField& seg_flow, const OdometryFrame& cur, const SE3& T_prev_cur,
                         bool camera_motion, const cv::Mat& movers = {}) const;
  // 255 where the flow fails scores.flow_consistency_px's check (segmentation level); empty when off.
  cv::Mat inconsistentAt(const FrameCues& cues, const FlowField& seg_flow) const;
  // The pixels without depth that move on their own (MotionEstimate::moving_holes), after the rounds.
  cv::Mat movingHoles(const FlowField& seg_flow, const SegmentationInput& in, const MotionEstimate& estimate,
                      const cv::Mat& flow_inconsistent) const;
  // The surfaces around a hole are looked for within a square of 1/kHoleWindowFraction of the width.
  static constexpr int kHoleWindowFraction = 8;
  // Where the samples' points lay in the previous frame (its depth) against the static map's depth
  // rendered for it and its scores (segmentation level; empty background: no relations).
  std::vector<MapRelation> mapRelations(const cv::Mat& previous_depth, const cv::Mat& previous_background,
                                        const cv::Mat& previous_scores, const FlowCorrespondences& samples) const;
  void restartFromFlow(const SegmentationInput& in, const FlowField& flow, const FlowField& seg_flow,
                       const cv::Mat& previous_background, MotionEstimate& estimate, Timings& timings);
  // Which pixels are the split's mover: its own (the background's motion leaves them beyond
  // 2 inlier_px, the mover's explains them within half of that), or, at the start, those the
  // background's motion leaves beyond inlier_px and the mover's explains better.
  enum class MoverRule { kOwn, kBetterExplained };
  // 1 on the split's mover, 0 elsewhere (CV_32F at the segmentation level).
  cv::Mat moverScores(const FlowField& seg_flow, const OdometryFrame& cur, const FlowMotionSplit& split,
                      MoverRule rule) const;
  // The static map's depth at the current estimate, its occlusion r_M and agreement a_M (empty when off).
  struct MapEvidence {
    cv::Mat background, r_M, a_M;
  };
  MapEvidence mapEvidence(const SegmentationInput& in, const SE3& T_world_cur, const RgbdFrame& seg_frame,
                          Timings& timings) const;
  // r_M without the pixels whose point an earlier scored frame saw as a static surface (past_views_).
  cv::Mat withheldWhereSeenStatic(const cv::Mat& r_M, const cv::Mat& depth, const SE3& T_world_cur, double timestamp,
                                  Timings& timings) const;
  // p_i (scores.temporal_prior): the previous frame's scores carried to the current frame at the
  // estimate, NaN where none lands; after a restart from the flow only its movers
  // (scores.restart_keeps_movers) or none. Empty without previous scores or the prior.
  cv::Mat carriedPrior(const SegmentationInput& in, const MotionEstimate& estimate) const;
  void scoreRounds(const SegmentationInput& in, const FlowField& seg_flow, const FlowField& seg_long_flow,
                   const cv::Mat& flow_inconsistent, const ClusterGraph& graph, MotionEstimate& estimate,
                   Timings& timings);
  // The flow from the current frame to the oldest kept one (scores.long_baseline_frames back),
  // chained through the kept frames' flows, NaN where that frame saw something nearer (hiddenIn);
  // empty until that many are kept, or when the camera turned more than the bound since.
  FlowField longBaselineFlow(const FlowField& seg_flow, const SegmentationInput& in, const MotionEstimate& estimate) const;
  // r_F of that flow at the current estimate (relative to its own frame error), scaled to at most
  // the larger of scores.long_baseline_noise_px and the median of the frame pair's r_pair; empty
  // without it.
  cv::Mat longBaselineResidual(const FlowField& seg_long_flow, const OdometryFrame& cur, const SE3& T_world_cur,
                               const cv::Mat& r_pair, const cv::Mat& movers) const;
  // Keeps the scored frame for the long baseline; a frame whose odometry failed, or that does not
  // follow the last kept one, empties the window first.
  void keepForLongBaseline(const SegmentationInput& in, const FlowField& seg_flow, const MotionEstimate& estimate);
  // The current frame's intensity and depth at the segmentation level.
  RgbdFrame segmentationFrame(const RgbdFrame& frame, const OdometryFrame& cur) const;

  SystemConfig config_;
  CameraIntrinsics camera_;
  CameraIntrinsics seg_camera_;
  DenseOdometry odometry_;
  DenseOdometry refine_odometry_;  // the rounds' re-estimates (refine_iterations per level)
  std::unique_ptr<OpticalFlow> flow_;
  std::unique_ptr<Clusterer> clusterer_;
  cv::Mat background_;  // the static map's depth rendered for the last scored frame (mapEvidence)
  MotionMemory memory_;  // where objects moved, for the scores' model term (scores.model_memory_s)
  PastViews past_views_;  // what earlier frames saw, for the same term (scores.model_views)
  HeldMovers held_movers_;  // movers seen moving clearly, held where they stand (scores.hold_seen_moving_s)
  SensorBandMedian sensor_band_;  // the run's frames' bands (segmentation level)
  struct LongBaselineFrame {
    FlowField flow;  // to its previous frame, at the segmentation level
    cv::Mat depth;   // at the segmentation level, for hiddenIn
    SE3 T_world_cam;
    double timestamp;
  };
  std::deque<LongBaselineFrame> long_baseline_;  // the last scores.long_baseline_frames scored frames
};

}  // namespace ff
