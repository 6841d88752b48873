#include "flowfusion/pipeline/segmentation_loop.h"

#include <cmath>
#include <limits>
#include <tuple>

#include "flowfusion/flow/flow_motion.h"
#include "flowfusion/flow/flow_residual.h"
#include "flowfusion/segmentation/dynamic_score.h"
#include "flowfusion/segmentation/score_carry.h"

namespace ff {

namespace {

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
      clusterer_(makeClusterer(config.clustering)) {}

cv::Mat SegmentationLoop::flowResidualAt(const FlowField& flow, const OdometryFrame& cur, const SE3& T_prev_cur) const {
  const int level = config_.pipeline.segmentation_level;
  return flowResidual(flow, egoFlow(cur.level(level).depth, seg_camera_, T_prev_cur)) * std::ldexp(1.0, level);
}

FlowField SegmentationLoop::computeFlow(const RgbdFrame& cur, const RgbdFrame& previous) {
  return flow_->compute(cur.intensity, previous.intensity);
}

void SegmentationLoop::run(const SegmentationInput& in, const FlowField& flow, MotionEstimate& estimate,
                           Timings& timings) {
  if (config_.consensus.enabled) restartFromFlow(in, flow, estimate, timings);
  if (estimate.odometry.ok) scoreRounds(in, flow, estimate, timings);
}

void SegmentationLoop::restartFromFlow(const SegmentationInput& in, const FlowField& flow, MotionEstimate& estimate,
                                       Timings& timings) {
  std::optional<SE3> T_prev_cur_flow;
  {
    StageTimer timer(timings, "consensus");
    T_prev_cur_flow = flowConsensusMotion(flow, in.frame.depth, camera_,
                                          in.T_target_prev.inverse() * estimate.T_target_cur, config_.consensus);
  }
  if (!T_prev_cur_flow) return;
  // The carried scores belong to the motion just rejected: the flow's own split replaces them.
  const cv::Mat outliers = flowResidualAt(flow, in.cur, *T_prev_cur_flow) > config_.consensus.inlier_px;
  cv::Mat flow_scores;
  outliers.convertTo(flow_scores, CV_32F, 1.0 / 255);
  StageTimer timer(timings, "odometry");
  const OdometryResult again = odometry_.estimate(in.cur, *in.target.odo, in.T_target_prev * *T_prev_cur_flow,
                                                  staticWeights(flow_scores), *in.target.weights);
  if (!again.ok) return;
  estimate.odometry = again;
  estimate.T_target_cur = again.T_target_source;
  estimate.scores = flow_scores;
  estimate.restarted_from_flow = true;
}

std::pair<cv::Mat, cv::Mat> SegmentationLoop::mapEvidence(const SegmentationInput& in, const SE3& T_world_cur,
                                                          const RgbdFrame& seg_frame, Timings& timings) const {
  const ScoreConfig& s = config_.scores;
  cv::Mat r_M, a_M;
  if (!in.map || in.map->size() == 0 || (s.alpha_M <= 0 && s.model_agreement <= 0)) return {r_M, a_M};
  StageTimer timer(timings, "prediction");
  // What lies in front of the static map is not background, what coincides with it is. The
  // surfels' intensity only serves the agreement.
  const bool agreement = s.model_agreement > 0;
  cv::Mat background_intensity;
  const cv::Mat background =
      in.map->predictStableDepth(T_world_cur, seg_camera_, agreement ? &background_intensity : nullptr);
  if (s.alpha_M > 0) r_M = modelOcclusion(seg_frame.depth, background, s.model_margin);
  if (agreement)
    a_M = modelAgreement(seg_frame.depth, background, s.agreement_margin, seg_frame.intensity, background_intensity,
                         s.agreement_intensity);
  return {r_M, a_M};
}

void SegmentationLoop::scoreRounds(const SegmentationInput& in, const FlowField& flow, MotionEstimate& estimate,
                                   Timings& timings) {
  const PipelineOptions& opt = config_.pipeline;
  const int level = opt.segmentation_level;
  RgbdFrame seg_frame;
  seg_frame.timestamp = in.frame.timestamp;
  seg_frame.intensity = in.cur.level(level).intensity;
  seg_frame.depth = in.cur.level(level).depth;
  ClusterGraph graph;
  {
    StageTimer timer(timings, "clustering");
    graph = clusterer_->cluster(seg_frame, seg_camera_);
  }
  ResidualImages res;
  std::tie(res.r_M, res.a_M) = mapEvidence(in, in.target.T_world_target * estimate.T_target_cur, seg_frame, timings);
  if (config_.scores.temporal_prior > 0 && !in.previous.scores.empty() && !estimate.restarted_from_flow) {
    const SE3 T_prev_cur = in.T_target_prev.inverse() * estimate.T_target_cur;
    res.prior = carryScores(in.previous.scores, in.previous.depthAt(level), seg_camera_, T_prev_cur.inverse(),
                            std::numeric_limits<float>::quiet_NaN());
  }
  for (int round = 0; round < opt.max_iterations; ++round) {
    {
      StageTimer timer(timings, "scores");
      const PixelResiduals pr = computePixelResiduals(in.cur, *in.target.odo, estimate.T_target_cur, level,
                                                      config_.odometry, *in.target.weights);
      res.r_I = pr.abs_intensity;
      res.r_D = pr.abs_depth;
      res.r_F = flowResidualAt(flow, in.cur, in.T_target_prev.inverse() * estimate.T_target_cur);
      estimate.scores = pixelScores(graph, computeDynamicScores(graph, res, config_.scores));
    }
    StageTimer timer(timings, "odometry");
    const OdometryResult again =
        refine_odometry_.estimate(in.cur, *in.target.odo, estimate.T_target_cur, staticWeights(estimate.scores),
                                  *in.target.weights, opt.refine_coarsest_level);
    estimate.rounds = round + 1;
    if (!again.ok) break;
    const bool done = converged(estimate.T_target_cur, again.T_target_source, opt);
    estimate.T_target_cur = again.T_target_source;
    if (done) break;
  }
}

}  // namespace ff
