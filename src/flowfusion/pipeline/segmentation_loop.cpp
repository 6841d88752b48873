#include "flowfusion/pipeline/segmentation_loop.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <utility>

#include "flowfusion/flow/flow_motion.h"
#include "flowfusion/flow/flow_residual.h"
#include "flowfusion/segmentation/depth_holes.h"
#include "flowfusion/segmentation/dynamic_score.h"
#include "flowfusion/segmentation/score_carry.h"
#include "flowfusion/segmentation/score_evidence.h"
#include "flowfusion/segmentation/small_regions.h"

namespace ff {

namespace {

// The median of the clusters' mean depths, metres (0 without a cluster with depth).
double medianClusterDepth(const ClusterGraph& graph) {
  std::vector<float> depths;
  for (const float d : graph.mean_depth)
    if (d > 0) depths.push_back(d);
  if (depths.empty()) return 0;
  std::nth_element(depths.begin(), depths.begin() + depths.size() / 2, depths.end());
  return depths[depths.size() / 2];
}

OdometryConfig refineConfig(const SystemConfig& c) {
  OdometryConfig o = c.odometry;
  o.max_iterations = o.max_iterations_finest = c.pipeline.refine_iterations;
  return o;
}

bool converged(const SE3& a, const SE3& b, const PipelineOptions& p) {
  const SE3 d = a.inverse() * b;
  return translationNorm(d) < p.converged_translation && rotationAngleDeg(d) < p.converged_rotation_deg;
}

}  // namespace

SegmentationLoop::SegmentationLoop(const SystemConfig& config, const CameraIntrinsics& camera)
    : config_(config),
      camera_(camera),
      seg_camera_(camera.atLevel(config.pipeline.segmentation_level)),
      odometry_(config.odometry),
      refine_odometry_(refineConfig(config)),
      flow_(makeOpticalFlow(config.flow)),
      clusterer_(makeClusterer(config.clustering)),
      memory_(config.scores.model_memory_s, seg_camera_),
      past_views_(seg_camera_, config.scores.model_view_every_frames, config.scores.model_views),
      held_movers_(config.scores.hold_seen_moving_s) {}

cv::Mat SegmentationLoop::flowResidualAt(const FlowField& seg_flow, const OdometryFrame& cur,
                                         const SE3& T_prev_cur, bool camera_motion, const cv::Mat& movers) const {
  const int level = config_.pipeline.segmentation_level;
  const cv::Mat ego = egoFlow(cur.level(level).depth, seg_camera_, T_prev_cur);
  // The error field's robust fit: a residual beyond a pixel of the segmentation level counts less.
  constexpr double kFieldScalePx = 1.0;
  const FlowErrorField field = camera_motion ? config_.scores.flow_error_field : FlowErrorField::kNone;
  const cv::Mat r = field == FlowErrorField::kAffineParallax
                        ? flowResidualWithoutPoseError(seg_flow, ego, cur.level(level).depth, seg_camera_,
                                                       kFieldScalePx, movers)
                    : field == FlowErrorField::kAffine ? flowResidualWithoutAffine(seg_flow, ego, kFieldScalePx)
                                                       : flowResidual(seg_flow, ego);
  return r * std::ldexp(1.0, level);
}

cv::Mat SegmentationLoop::inconsistentAt(const FrameCues& cues, const FlowField& seg_flow) const {
  if (cues.flow_back.uv.empty()) return {};
  const double tolerance_px = config_.scores.flow_consistency_px / std::ldexp(1.0, config_.pipeline.segmentation_level);
  return inconsistentFlow(seg_flow, resizeFlow(cues.flow_back, seg_flow.uv.size()), tolerance_px);
}

cv::Mat SegmentationLoop::movingHoles(const FlowField& seg_flow, const SegmentationInput& in,
                                      const MotionEstimate& estimate, const cv::Mat& flow_inconsistent) const {
  const double min_flow_px = config_.pipeline.mask_hole_flow_px;
  // Without a mover the written mask has nothing for a hole to lie beside.
  if (min_flow_px <= 0 || estimate.scores.empty() ||
      cv::countNonZero(estimate.scores > config_.pipeline.mask_threshold) == 0)
    return {};
  const int level = config_.pipeline.segmentation_level;
  const cv::Mat& depth = in.cur.level(level).depth;
  const cv::Mat band_left_out = config_.pipeline.mask_band_holes ? cv::Mat() : estimate.sensor_band;
  const cv::Mat holes = holesToTest(depth, in.cur.level(level).intensity, band_left_out);
  if (holes.empty()) return {};
  // What may lie in a hole: the surfaces around it, near and far, and the stable map's.
  const DepthAround around = depthAround(depth, (depth.cols / kHoleWindowFraction) | 1);
  std::vector<cv::Mat> depths{around.nearest, around.farthest};
  if (!background_.empty()) depths.push_back(background_);
  const SE3 T_prev_cur = in.T_target_prev.inverse() * estimate.T_target_cur;
  const cv::Mat r_static = relativeToFrameError(
      smallestFlowResidual(seg_flow, depths, seg_camera_, T_prev_cur) * std::ldexp(1.0, level),
      config_.scores.flow_error_px);
  return holesMovingOnTheirOwn(holes, r_static, flow_inconsistent, min_flow_px);
}

RgbdFrame SegmentationLoop::segmentationFrame(const RgbdFrame& frame, const OdometryFrame& cur) const {
  const int level = config_.pipeline.segmentation_level;
  RgbdFrame seg_frame;
  seg_frame.timestamp = frame.timestamp;
  seg_frame.intensity = cur.level(level).intensity;
  seg_frame.depth = cur.level(level).depth;
  return seg_frame;
}

FrameCues SegmentationLoop::computeCues(const RgbdFrame& frame, const OdometryFrame& cur, const RgbdFrame& previous) {
  FrameCues cues;
  auto start = std::chrono::steady_clock::now();
  cues.flow = flow_->compute(frame.intensity, previous.intensity);
  if (config_.scores.flow_consistency_px > 0) cues.flow_back = flow_->compute(previous.intensity, frame.intensity);
  cues.flow_ms = msSince(start);
  start = std::chrono::steady_clock::now();
  cues.graph = clusterer_->cluster(segmentationFrame(frame, cur), seg_camera_);
  cues.clustering_ms = msSince(start);
  return cues;
}

void SegmentationLoop::run(const SegmentationInput& in, const FrameCues& cues, MotionEstimate& estimate,
                           Timings& timings) {
  const FlowField& flow = cues.flow;
  // The static map's depth rendered for the previous frame; none when that frame was not scored.
  const cv::Mat previous_background = std::exchange(background_, cv::Mat());
  // The flow at the segmentation level, resampled once for all of this frame's residuals.
  const FlowField seg_flow = resizeFlow(flow, cv::Size(seg_camera_.width, seg_camera_.height));
  sensor_band_.add(SensorBand::of(in.cur.level(config_.pipeline.segmentation_level).depth));
  estimate.sensor_band = sensor_band_.median().pixels(seg_flow.uv.size());
  if (config_.consensus.enabled) restartFromFlow(in, flow, seg_flow, previous_background, estimate, timings);
  if (estimate.odometry.ok) {
    StageTimer timer(timings, "flow");
    const FlowField seg_long_flow = longBaselineFlow(seg_flow, in, estimate);
    timer.stop();
    const cv::Mat inconsistent = inconsistentAt(cues, seg_flow);
    scoreRounds(in, seg_flow, seg_long_flow, inconsistent, cues.graph, estimate, timings);
    StageTimer holes_timer(timings, "scores");
    estimate.moving_holes = movingHoles(seg_flow, in, estimate, inconsistent);
  }
  keepForLongBaseline(in, seg_flow, estimate);
}

FlowField SegmentationLoop::longBaselineFlow(const FlowField& seg_flow, const SegmentationInput& in,
                                             const MotionEstimate& estimate) const {
  const ScoreConfig& c = config_.scores;
  if (c.long_baseline_frames == 0 || static_cast<int>(long_baseline_.size()) < c.long_baseline_frames) return {};
  const LongBaselineFrame& past = long_baseline_.front();
  const SE3 T_past_cur = past.T_world_cam.inverse() * in.target.T_world_target * estimate.T_target_cur;
  if (rotationAngleDeg(T_past_cur) > c.long_baseline_max_turn_deg) return {};
  // The current frame's flow to its previous, then the kept frames' own, newest first; the
  // oldest kept frame's flow leads further back than the baseline.
  std::vector<const FlowField*> steps{&seg_flow};
  for (auto kept = long_baseline_.rbegin(); kept + 1 != long_baseline_.rend(); ++kept) steps.push_back(&kept->flow);
  FlowField chained = chainFlows(steps);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  chained.uv.setTo(cv::Scalar(nan, nan), hiddenIn(in.cur.level(config_.pipeline.segmentation_level).depth, past.depth,
                                                  seg_camera_, T_past_cur, c.model_margin));
  return chained;
}

cv::Mat SegmentationLoop::longBaselineResidual(const FlowField& seg_long_flow, const OdometryFrame& cur,
                                               const SE3& T_world_cur, const cv::Mat& r_pair,
                                               const cv::Mat& movers) const {
  if (seg_long_flow.uv.empty()) return {};
  const SE3 T_past_cur = long_baseline_.front().T_world_cam.inverse() * T_world_cur;
  // The chain's own error brought to the frame's typical one and, with long_baseline_noise_px, to
  // the pair's, or to that setting where the pair's is below it.
  return relativeToFrameError(flowResidualAt(seg_long_flow, cur, T_past_cur, true, movers),
                              longBaselineTypicalErrorPx(config_.scores, finiteMedian(r_pair)));
}

void SegmentationLoop::keepForLongBaseline(const SegmentationInput& in, const FlowField& seg_flow,
                                           const MotionEstimate& estimate) {
  const int frames = config_.scores.long_baseline_frames;
  if (frames == 0) return;
  if (!estimate.odometry.ok) {
    long_baseline_.clear();
    return;
  }
  if (!long_baseline_.empty() && long_baseline_.back().timestamp != in.previous.frame.timestamp) long_baseline_.clear();
  long_baseline_.push_back({seg_flow, in.cur.level(config_.pipeline.segmentation_level).depth,
                            in.target.T_world_target * estimate.T_target_cur, in.frame.timestamp});
  while (static_cast<int>(long_baseline_.size()) > frames) long_baseline_.pop_front();
}

void SegmentationLoop::restartFromFlow(const SegmentationInput& in, const FlowField& flow, const FlowField& seg_flow,
                                       const cv::Mat& previous_background, MotionEstimate& estimate, Timings& timings) {
  // Nothing is known of the movers yet (the first frame pair, or after a frame left unscored): the
  // odometry had no weights to keep a mover out, so the flow is split whatever the odometry
  // explains, and the split's mover group is taken for the movers.
  const bool start = in.previous.scores.empty();
  std::optional<FlowMotionSplit> split;
  FlowCorrespondences samples;
  std::vector<MapRelation> relation;
  const SE3 T_prev_cur = in.T_target_prev.inverse() * estimate.T_target_cur;
  {
    StageTimer timer(timings, "consensus");
    // At the start the larger group counts only its measured (textured) samples (start_min_texture).
    samples = sampleFlowCorrespondences(flow, in.frame.depth, camera_, config_.consensus.grid_step,
                                        start ? in.frame.intensity : cv::Mat(), config_.consensus.start_min_texture);
    relation = mapRelations(in.previous.frame.depth, previous_background, in.previous.scores, samples);
    if (!start) {
      split = splitFlowAgainst(samples, camera_, T_prev_cur, config_.consensus, relation);
    } else if (FlowMotionSplit s = splitFlowMotions(samples, camera_, config_.consensus, {T_prev_cur}, relation); s.ok) {
      split = std::move(s);
    }
  }
  if (!split) return;
  const bool start_movers = start && showsMoverGroup(*split, samples, camera_, config_.consensus, in.frame.intensity);
  const bool shows_mover = start_movers || showsMover(*split, samples, config_.consensus);
  const bool misled = start_movers || misledOdometry(samples, camera_, *split, T_prev_cur, config_.consensus, relation);
  if (!shows_mover && !misled) return;
  const cv::Mat mover =
      moverScores(seg_flow, in.cur, *split, start_movers ? MoverRule::kBetterExplained : MoverRule::kOwn);
  if (shows_mover) estimate.flow_mover = mover;
  estimate.flow_mover_holds = start_movers;
  if (!misled) return;
  // The carried scores weighted the motion just rejected: the restarted odometry is weighted by the
  // split's mover alone. Their movers come back as the prior once carried with the restarted
  // motion (carriedPrior, scores.restart_keeps_movers).
  StageTimer timer(timings, "odometry");
  const OdometryResult again = odometry_.estimate(in.cur, *in.target.odo, in.T_target_prev * split->T_b_a_background,
                                                  staticWeights(mover), *in.target.weights);
  if (!again.ok) return;
  estimate.odometry = again;
  estimate.T_target_cur = again.T_target_source;
  estimate.target_depth_offset = again.target_depth_offset;
  estimate.scores = mover;
  estimate.restarted_from_flow = true;
}

std::vector<MapRelation> SegmentationLoop::mapRelations(const cv::Mat& previous_depth, const cv::Mat& previous_background,
                                                        const cv::Mat& previous_scores,
                                                        const FlowCorrespondences& samples) const {
  if (previous_background.empty()) return {};
  const bool movers_in_front = config_.consensus.previous_movers_in_front && !previous_scores.empty();
  // The previous frame's depth where the flow lands, against the map's stable surfaces there.
  const double to_level = std::ldexp(1.0, -config_.pipeline.segmentation_level);
  std::vector<MapRelation> relation(samples.size(), MapRelation::kUnknown);
  for (size_t k = 0; k < samples.size(); ++k) {
    const cv::Point2f& b = samples.pixels_b[k];
    const int u = std::clamp(static_cast<int>(std::lround(b.x)), 0, previous_depth.cols - 1);
    const int v = std::clamp(static_cast<int>(std::lround(b.y)), 0, previous_depth.rows - 1);
    const int ul = std::min(static_cast<int>(b.x * to_level), previous_background.cols - 1);
    const int vl = std::min(static_cast<int>(b.y * to_level), previous_background.rows - 1);
    const float d = previous_depth.at<float>(v, u), m = previous_background.at<float>(vl, ul);
    if (!(d > 0)) continue;
    if (movers_in_front && previous_scores.at<float>(vl, ul) > kDynamicScore) {
      relation[k] = MapRelation::kInFront;
      continue;
    }
    if (!(m > 0)) continue;
    const double margin = config_.scores.model_margin * m;
    if (std::abs(d - m) <= margin)
      relation[k] = MapRelation::kOnMap;
    else if (d < m - margin)
      relation[k] = MapRelation::kInFront;
  }
  return relation;
}

cv::Mat SegmentationLoop::moverScores(const FlowField& seg_flow, const OdometryFrame& cur, const FlowMotionSplit& split,
                                      MoverRule rule) const {
  const bool own = rule == MoverRule::kOwn;
  const double off_px = (own ? 2 : 1) * config_.consensus.inlier_px;
  const cv::Mat r_background = flowResidualAt(seg_flow, cur, split.T_b_a_background, false);
  const cv::Mat r_mover = flowResidualAt(seg_flow, cur, split.T_b_a_mover, false);
  const cv::Mat mover = (r_background > off_px) & (r_mover < (own ? 0.5 : 1.0) * r_background);
  cv::Mat scores;
  mover.convertTo(scores, CV_32F, 1.0 / 255);
  return scores;
}

SegmentationLoop::MapEvidence SegmentationLoop::mapEvidence(const SegmentationInput& in, const SE3& T_world_cur,
                                                           const RgbdFrame& seg_frame, Timings& timings) const {
  const ScoreConfig& s = config_.scores;
  MapEvidence e;
  if (!in.map || in.map->size() == 0 || (s.alpha_M <= 0 && s.model_agreement <= 0)) return e;
  StageTimer timer(timings, "prediction");
  // What lies in front of the static map is not background, what coincides with it is. The
  // surfels' intensity only serves the agreement.
  const bool agreement = s.model_agreement > 0;
  cv::Mat background_intensity;
  e.background = in.map->predictStableDepth(T_world_cur, seg_camera_, agreement ? &background_intensity : nullptr);
  if (s.alpha_M > 0) e.r_M = modelOcclusion(seg_frame.depth, e.background, s.model_margin);
  if (agreement)
    e.a_M = modelAgreement(seg_frame.depth, e.background, s.agreement_margin, seg_frame.intensity, background_intensity,
                           s.agreement_intensity);
  return e;
}

cv::Mat SegmentationLoop::withheldWhereSeenStatic(const cv::Mat& r_M, const cv::Mat& depth, const SE3& T_world_cur,
                                                  double timestamp, Timings& timings) const {
  if (r_M.empty() || past_views_.empty()) return r_M;
  StageTimer timer(timings, "scores");
  const ScoreConfig& s = config_.scores;
  return PastViews::withoutStaticThere(
      r_M, past_views_.sight(depth, T_world_cur, timestamp, s.model_view_min_age_s, s.model_margin, r_M > 0));
}

cv::Mat SegmentationLoop::carriedPrior(const SegmentationInput& in, const MotionEstimate& estimate) const {
  const ScoreConfig& s = config_.scores;
  if (s.temporal_prior <= 0 || in.previous.scores.empty()) return {};
  if (estimate.restarted_from_flow && !s.restart_keeps_movers) return {};
  constexpr float kNone = std::numeric_limits<float>::quiet_NaN();
  const SE3 T_prev_cur = in.T_target_prev.inverse() * estimate.T_target_cur;
  cv::Mat prior = carryScores(in.previous.scores, in.previous.depthAt(config_.pipeline.segmentation_level),
                              seg_camera_, T_prev_cur.inverse(), kNone);
  if (estimate.restarted_from_flow) prior.setTo(kNone, prior <= static_cast<float>(kDynamicScore));
  return prior;
}

void SegmentationLoop::scoreRounds(const SegmentationInput& in, const FlowField& seg_flow,
                                   const FlowField& seg_long_flow, const cv::Mat& flow_inconsistent,
                                   const ClusterGraph& graph, MotionEstimate& estimate, Timings& timings) {
  const PipelineOptions& opt = config_.pipeline;
  const int level = opt.segmentation_level;
  const RgbdFrame seg_frame = segmentationFrame(in.frame, in.cur);
  ResidualImages res;
  const SE3 T_world_cur = in.target.T_world_target * estimate.T_target_cur;
  MapEvidence evidence = mapEvidence(in, T_world_cur, seg_frame, timings);
  res.r_D_from_map = in.target.from_model;
  res.r_M = withheldWhereSeenStatic(evidence.r_M, seg_frame.depth, T_world_cur, in.frame.timestamp, timings);
  res.a_M = evidence.a_M;
  if (!res.a_M.empty()) estimate.map_agreement = res.a_M > 0.5f;  // 1 agrees, 0 or NaN does not
  background_ = evidence.background;
  res.prior = carriedPrior(in, estimate);
  const cv::Mat held = held_movers_.carried(in.previous.depthAt(level), in.previous.frame.timestamp, seg_camera_,
                                            in.T_target_prev.inverse() * estimate.T_target_cur, seg_frame.depth,
                                            in.frame.timestamp, res.a_M);
  res.memory = memory_.recall(in.target.T_world_target * estimate.T_target_cur, in.frame.timestamp);
  if (!estimate.flow_mover.empty()) {
    // The flow's own mover is a mover a priori; elsewhere the carried scores, if any.
    if (res.prior.empty()) res.prior = cv::Mat(estimate.flow_mover.size(), CV_32F, std::numeric_limits<float>::quiet_NaN());
    res.prior.setTo(1.f, estimate.flow_mover > 0);
  }
  const double dt_s = in.frame.timestamp - in.previous.frame.timestamp;
  // How far apart the depth may be taken from the colour: their stamps, and the allowance.
  const double depth_offset_s =
      std::abs(in.frame.timestamp - in.frame.depthTime()) + config_.scores.depth_offset_ms / 1000;
  const double depth_m = medianClusterDepth(graph);
  DynamicScores scores;
  for (int round = 0; round < opt.max_iterations; ++round) {
    if (round > 0 && std::chrono::steady_clock::now() > in.deadline) break;
    {
      StageTimer timer(timings, "scores");
      const SE3 T_prev_cur = in.T_target_prev.inverse() * estimate.T_target_cur;
      const int depth_window_px = depthOffsetPx(T_prev_cur, dt_s, seg_camera_.fx, depth_m, depth_offset_s,
                                                config_.scores.depth_window_px);
      const PixelResiduals pr = computePixelResiduals(in.cur, *in.target.odo, estimate.T_target_cur, level,
                                                      config_.odometry, *in.target.weights,
                                                      config_.scores.target_mover_margin_px, depth_window_px,
                                                      estimate.target_depth_offset);
      res.r_I = pr.abs_intensity;
      res.r_D = pr.abs_depth;
      res.on_target_mover = pr.on_target_mover;
      // The pixels the scores hold for movers so far stay out of the residual's error field.
      const cv::Mat movers = estimate.scores.empty() ? cv::Mat() : cv::Mat(estimate.scores > kDynamicScore);
      const cv::Mat r_pair = relativeToFrameError(flowResidualAt(seg_flow, in.cur, T_prev_cur, true, movers),
                                                  config_.scores.flow_error_px);
      res.r_F = largerResidual(r_pair, longBaselineResidual(seg_long_flow, in.cur,
                                                            in.target.T_world_target * estimate.T_target_cur, r_pair,
                                                            movers));
      if (!flow_inconsistent.empty()) res.r_F.setTo(std::numeric_limits<float>::quiet_NaN(), flow_inconsistent);
      scores = computeDynamicScores(graph, res, config_.scores);
      estimate.scores = pixelScores(graph, scores);
      if (estimate.flow_mover_holds) estimate.scores = cv::max(estimate.scores, estimate.flow_mover);
      if (!held.empty()) estimate.scores = cv::max(estimate.scores, held);
    }
    StageTimer timer(timings, "odometry");
    const OdometryResult again =
        refine_odometry_.estimate(in.cur, *in.target.odo, estimate.T_target_cur, staticWeights(estimate.scores),
                                  *in.target.weights, opt.refine_coarsest_level,
                                  estimate.target_depth_offset);
    estimate.rounds = round + 1;
    if (!again.ok) break;
    const bool done = converged(estimate.T_target_cur, again.T_target_source, opt);
    estimate.T_target_cur = again.T_target_source;
    estimate.target_depth_offset = again.target_depth_offset;
    if (done) break;
  }
  if (opt.cluster_log) estimate.cluster_log = clusterLog(graph, res, scores);
  if (opt.mask_keep_flow_px > 0 && (opt.mask_min_region > 0 || held_movers_.enabled()))
    estimate.seen_moving =
        seenMovingClusters(graph, res, scores, opt.mask_keep_flow_px, opt.mask_keep_max_agreement);
  if (!estimate.seen_moving.empty()) held_movers_.remember(held, estimate.seen_moving, in.frame.timestamp);
  const SE3 T_world_scored = in.target.T_world_target * estimate.T_target_cur;
  memory_.remember(graph, scores, seg_frame.depth, T_world_scored, in.frame.timestamp);
  past_views_.add(seg_frame.depth, estimate.scores, T_world_scored, in.frame.timestamp);
}

}  // namespace ff
