#include "flowfusion/pipeline/flowfusion_system.h"

#include <chrono>
#include <cmath>
#include <optional>
#include <opencv2/imgproc.hpp>

#include "flowfusion/core/error.h"
#include "flowfusion/core/image_pyramid.h"
#include "flowfusion/flow/flow_residual.h"

namespace ff {

void validate(const SystemConfig& c) {
  const PipelineOptions& p = c.pipeline;
  if (p.tracking != "frame_to_frame" && p.tracking != "frame_to_keyframe" && p.tracking != "frame_to_model")
    throw InputError("pipeline.tracking must be frame_to_frame, frame_to_keyframe or frame_to_model, got '" +
                     p.tracking + "'");
  if (p.tracking == "frame_to_model" && !p.fusion)
    throw InputError("pipeline.tracking frame_to_model needs pipeline.fusion = true (the map is the model)");
  if (p.max_iterations < 1) throw InputError("pipeline.max_iterations must be at least 1");
  if (p.refine_coarsest_level < -1 || p.refine_coarsest_level >= c.odometry.levels)
    throw InputError("pipeline.refine_coarsest_level must be -1 (the coarsest) or in [0, odometry.levels)");
  if (p.fusion_every < 1) throw InputError("pipeline.fusion_every must be at least 1");
  if (p.refine_iterations < 1) throw InputError("pipeline.refine_iterations must be at least 1");
  if (p.segmentation_level < 0 || p.segmentation_level >= c.odometry.levels)
    throw InputError("pipeline.segmentation_level must be in [0, odometry.levels)");
  if (!(p.mask_threshold > 0 && p.mask_threshold < 1)) throw InputError("pipeline.mask_threshold must be in (0, 1)");
  if (!(p.model_min_valid_fraction >= 0 && p.model_min_valid_fraction <= 1))
    throw InputError("pipeline.model_min_valid_fraction must be in [0, 1]");
  validate(c.odometry);
  validate(c.consensus);
  validateFusionConfig(c.fusion);
  makeOpticalFlow(c.flow);
  makeClusterer(c.clustering);
  if (!(c.scores.theta_t > c.scores.theta_b)) throw InputError("scores.theta_t must be greater than scores.theta_b");
  if (!(c.scores.alpha_M >= 0)) throw InputError("scores.alpha_M must be >= 0 (0 turns the model term off)");
  if (!(c.scores.model_margin >= 0)) throw InputError("scores.model_margin must be >= 0");
  if (!(c.scores.model_motion_delta >= 0)) throw InputError("scores.model_motion_delta must be >= 0");
  if (!(c.scores.model_agreement >= 0 && c.scores.model_agreement <= 1))
    throw InputError("scores.model_agreement must be in [0, 1] (0 turns the map's static evidence off)");
  if (!(c.scores.agreement_margin > 0)) throw InputError("scores.agreement_margin must be > 0");
  if (!(c.scores.agreement_intensity > 0))
    throw InputError("scores.agreement_intensity must be > 0 (1 compares depth alone)");
  if (!(c.scores.temporal_prior >= 0)) throw InputError("scores.temporal_prior must be >= 0 (0 turns the prior off)");
}

struct FlowFusionSystem::Previous {
  RgbdFrame frame;
  OdometryFrame odo;
  SE3 T_world_cam;
  cv::Mat scores;  // b per pixel at the segmentation level, empty when none
  bool from_model = false;  // odo holds the map's depth predicted at T_world_cam

  // Depth image at pyramid `level` (level 0 is the input frame's own).
  const cv::Mat& depthAt(int level) const { return level == 0 ? frame.depth : odo.level(level).depth; }
};

namespace {

double since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// Scores of the previous frame carried into the current one: each previous pixel's score is
// splatted to where the motion takes it (forward warp with its depth), nearest surface wins;
// `fill` where nothing lands.
cv::Mat carryScores(const cv::Mat& prev_scores, const cv::Mat& prev_depth, const CameraIntrinsics& cam,
                    const SE3& T_cur_prev, float fill) {
  cv::Mat out(prev_scores.size(), CV_32F, cv::Scalar(fill));
  cv::Mat zbuf(prev_scores.size(), CV_32F, cv::Scalar(std::numeric_limits<float>::infinity()));
  for (int y = 0; y < prev_depth.rows; ++y)
    for (int x = 0; x < prev_depth.cols; ++x) {
      const float b = prev_scores.at<float>(y, x);
      const float z = prev_depth.at<float>(y, x);
      if (z <= 0) continue;
      const Eigen::Vector3d q = T_cur_prev * cam.backproject(x, y, z);
      if (q.z() <= 0) continue;
      const Eigen::Vector2d uv = cam.project(q);
      // Splat to the 2x2 neighbourhood so that no holes open up.
      for (int dy = 0; dy <= 1; ++dy)
        for (int dx = 0; dx <= 1; ++dx) {
          const int u = static_cast<int>(uv.x()) + dx, v = static_cast<int>(uv.y()) + dy;
          if (u < 0 || v < 0 || u >= out.cols || v >= out.rows) continue;
          if (q.z() < zbuf.at<float>(v, u)) {
            zbuf.at<float>(v, u) = static_cast<float>(q.z());
            out.at<float>(v, u) = b;
          }
        }
    }
  return out;
}

double depthTime(const RgbdFrame& f) { return std::isnan(f.depth_timestamp) ? f.timestamp : f.depth_timestamp; }

cv::Mat staticWeights(const cv::Mat& scores) {
  cv::Mat w;
  cv::subtract(cv::Scalar(1.0), scores, w);
  return w;
}

bool converged(const SE3& a, const SE3& b, const PipelineOptions& p) {
  const SE3 d = a.inverse() * b;
  return translationNorm(d) < p.converged_translation && rotationAngleDeg(d) < p.converged_rotation_deg;
}

// The flow's rigid motion T_prev_cur when it explains at least min_gain of the sampled flow more
// than `T_prev_cur_odometry` does.
std::optional<SE3> flowConsensusMotion(const FlowField& flow, const cv::Mat& depth, const CameraIntrinsics& camera,
                                       const SE3& T_prev_cur_odometry, const ConsensusConfig& cfg) {
  const FlowCorrespondences c = sampleFlowCorrespondences(flow, depth, camera, cfg.grid_step);
  const double n = static_cast<double>(c.size());
  const int explained = countFlowInliers(c, camera, T_prev_cur_odometry, cfg.inlier_px);
  // RANSAC cannot win by min_gain when the odometry already explains this much.
  if (explained >= (1.0 - cfg.min_gain) * n) return std::nullopt;
  const FlowMotion m = estimateFlowMotion(c, camera, cfg);
  if (!m.ok || m.inliers < explained + cfg.min_gain * n) return std::nullopt;
  return m.T_b_a;
}

OdometryConfig refineConfig(const SystemConfig& c) {
  OdometryConfig o = c.odometry;
  o.max_iterations = o.max_iterations_finest = c.pipeline.refine_iterations;
  return o;
}

}  // namespace

FlowFusionSystem::FlowFusionSystem(const SystemConfig& config, const CameraIntrinsics& camera, const SE3& T_world_first)
    : config_(config),
      camera_(camera),
      odometry_((validate(config), config.odometry)),
      refine_odometry_(refineConfig(config)),
      T_world_first_(T_world_first) {
  if (config_.pipeline.segmentation) {
    flow_ = makeOpticalFlow(config_.flow);
    clusterer_ = makeClusterer(config_.clustering);
  }
  if (config_.pipeline.fusion) map_ = std::make_unique<StaticMap>(config_.fusion);
}

FlowFusionSystem::~FlowFusionSystem() = default;

std::optional<OdometryFrame> FlowFusionSystem::modelTarget(const Previous& source, const cv::Mat& keep) const {
  // Rendered at the odometry's finest level (the finer input levels are never aligned) and
  // brought to the input size, where the pyramid's 2x2 averages give it back unchanged.
  const int finest = config_.odometry.finest_level;
  const cv::Mat predicted = map_->predictDepth(source.T_world_cam, camera_.atLevel(finest));
  const double covered = cv::countNonZero(predicted > 0);
  const double needed = config_.pipeline.model_min_valid_fraction * cv::countNonZero(source.depthAt(finest) > 0);
  if (covered < needed) return std::nullopt;
  // The model's depth is averaged over many frames (less noise, less drift); its colour is
  // blurred by the surfel splats, so the frame's own image stays the photometric target.
  // Where the model has no surface, and at the `keep` pixels, the frame's depth stays.
  const RgbdFrame& frame = source.frame;
  cv::Mat depth;
  cv::resize(predicted, depth, frame.depth.size(), 0, 0, cv::INTER_NEAREST);
  frame.depth.copyTo(depth, depth <= 0);
  if (!keep.empty()) frame.depth.copyTo(depth, keep);
  return prepareOdometryFrame(frame.intensity, depth, camera_, config_.odometry);
}

FrameResult FlowFusionSystem::process(const RgbdFrame& frame) {
  const PipelineOptions& opt = config_.pipeline;
  if (frame.width() != camera_.width || frame.height() != camera_.height)
    throw InputError(frame.name + ": frame is " + std::to_string(frame.width()) + "x" +
                     std::to_string(frame.height()) + ", the camera is " + std::to_string(camera_.width) + "x" +
                     std::to_string(camera_.height));
  timings_.beginFrame(frame.timestamp);
  FrameResult result;
  result.timestamp = frame.timestamp;

  auto t0 = std::chrono::steady_clock::now();
  OdometryFrame cur = prepareOdometryFrame(frame.intensity, frame.depth, camera_, config_.odometry);
  timings_.add("odometry", since(t0));
  const int seg_level = opt.segmentation_level;
  const CameraIntrinsics seg_camera = camera_.atLevel(seg_level);
  const cv::Size seg_size(seg_camera.width, seg_camera.height);
  cv::Mat scores;  // b per pixel at the segmentation level

  if (!prev_) {
    result.T_world_cam = T_world_first_;
    result.message = "first frame";
  } else {
    // The target: the previous frame, the last keyframe, or the map's prediction at the previous
    // pose when it covers enough of the view. T_target_prev places the previous camera in it.
    OdometryFrame model;
    const OdometryFrame* target = &prev_->odo;
    SE3 T_world_target = prev_->T_world_cam;
    if (opt.tracking == "frame_to_keyframe" && keyframe_) {
      target = &keyframe_->odo;
      T_world_target = keyframe_->T_world_cam;
      result.used_model = keyframe_->from_model;
    }
    const SE3 T_target_prev = T_world_target.inverse() * prev_->T_world_cam;
    if (opt.tracking == "frame_to_model" && map_ && map_->size() > 0) {
      t0 = std::chrono::steady_clock::now();
      if (auto predicted = modelTarget(*prev_)) {
        model = std::move(*predicted);
        target = &model;
        result.used_model = true;
      }
      timings_.add("prediction", since(t0));
    }

    // T_target_cur: current-camera points into the target camera.
    const SE3 T_prev_cur_guess = opt.constant_velocity ? T_prev_cur_velocity_ : SE3::Identity();
    SE3 T_target_cur = T_target_prev * T_prev_cur_guess;
    const cv::Mat& prev_seg_depth = prev_->depthAt(seg_level);
    if (opt.segmentation && opt.carry_scores && !prev_->scores.empty())
      scores = carryScores(prev_->scores, prev_seg_depth, seg_camera, T_prev_cur_guess.inverse(), 0.f);
    t0 = std::chrono::steady_clock::now();
    const cv::Mat initial_weights = scores.empty() ? cv::Mat() : staticWeights(scores);
    OdometryResult odo = odometry_.estimate(cur, *target, T_target_cur, initial_weights);
    if (!odo.ok && result.used_model) {
      // A thin or wrong prediction: the previous frame is the safer target.
      target = &prev_->odo;
      T_world_target = prev_->T_world_cam;
      result.used_model = false;
      odo = odometry_.estimate(cur, *target, T_target_cur, initial_weights);
    }
    timings_.add("odometry", since(t0));
    if (odo.ok) T_target_cur = odo.T_cur_ref;

    FlowField flow;
    if (opt.segmentation) {
      t0 = std::chrono::steady_clock::now();
      flow = flow_->compute(frame.intensity, prev_->frame.intensity);
      timings_.add("flow", since(t0));
    }
    // r_F (Eq. 9) at the segmentation level under the motion T_prev_cur, in pixels of the input
    // image (ScoreConfig's units). The flow runs from the current to the previous image, whatever
    // the target.
    const double px_scale = std::ldexp(1.0, seg_level);
    const auto flowResidualAt = [&](const SE3& T_prev_cur) -> cv::Mat {
      return flowResidual(flow, egoFlow(cur.level(seg_level).depth, seg_camera, T_prev_cur)) * px_scale;
    };
    if (opt.segmentation && config_.consensus.enabled) {
      t0 = std::chrono::steady_clock::now();
      const auto T_prev_cur_flow = flowConsensusMotion(flow, frame.depth, camera_,
                                                       T_target_prev.inverse() * T_target_cur, config_.consensus);
      timings_.add("consensus", since(t0));
      if (T_prev_cur_flow) {
        // The carried scores belong to the motion just rejected: the flow's own split replaces them.
        const cv::Mat outliers = flowResidualAt(*T_prev_cur_flow) > config_.consensus.inlier_px;
        cv::Mat flow_scores;
        outliers.convertTo(flow_scores, CV_32F, 1.0 / 255);
        t0 = std::chrono::steady_clock::now();
        const OdometryResult again =
            odometry_.estimate(cur, *target, T_target_prev * *T_prev_cur_flow, staticWeights(flow_scores));
        timings_.add("odometry", since(t0));
        if (again.ok) {
          odo = again;
          T_target_cur = again.T_cur_ref;
          scores = flow_scores;
          result.restarted_from_flow = true;
          ++flow_restarts_;
        }
      }
    }

    if (opt.segmentation && odo.ok) {
      t0 = std::chrono::steady_clock::now();
      RgbdFrame seg_frame;
      seg_frame.timestamp = frame.timestamp;
      seg_frame.intensity = cur.level(seg_level).intensity;
      seg_frame.depth = cur.level(seg_level).depth;
      const ClusterGraph graph = clusterer_->cluster(seg_frame, seg_camera);
      timings_.add("clustering", since(t0));
      // The static map seen from the current estimate: what lies in front of it is not background,
      // what coincides with it is.
      cv::Mat r_M, a_M;
      if (map_ && map_->size() > 0 && (config_.scores.alpha_M > 0 || config_.scores.model_agreement > 0)) {
        t0 = std::chrono::steady_clock::now();
        // The surfels' intensity only serves the agreement.
        const bool agreement = config_.scores.model_agreement > 0;
        cv::Mat background_intensity;
        const cv::Mat background = map_->predictStableDepth(T_world_target * T_target_cur, seg_camera,
                                                            agreement ? &background_intensity : nullptr);
        if (config_.scores.alpha_M > 0) r_M = modelOcclusion(seg_frame.depth, background, config_.scores.model_margin);
        if (agreement)
          a_M = modelAgreement(seg_frame.depth, background, config_.scores.agreement_margin, seg_frame.intensity,
                               background_intensity, config_.scores.agreement_intensity);
        timings_.add("prediction", since(t0));
      }
      cv::Mat prior;
      if (config_.scores.temporal_prior > 0 && !prev_->scores.empty() && !result.restarted_from_flow) {
        const SE3 T_prev_cur = T_target_prev.inverse() * T_target_cur;
        prior = carryScores(prev_->scores, prev_seg_depth, seg_camera, T_prev_cur.inverse(),
                            std::numeric_limits<float>::quiet_NaN());
      }
      for (int round = 0; round < opt.max_iterations; ++round) {
        t0 = std::chrono::steady_clock::now();
        const PixelResiduals pr = computePixelResiduals(cur, *target, T_target_cur, seg_level, config_.odometry);
        ResidualImages res;
        res.r_I = pr.abs_intensity;
        res.r_D = pr.abs_depth;
        res.r_F = flowResidualAt(T_target_prev.inverse() * T_target_cur);
        res.r_M = r_M;
        res.a_M = a_M;
        res.prior = prior;
        const DynamicScores ds = computeDynamicScores(graph, res, config_.scores);
        scores = pixelScores(graph, ds);
        timings_.add("scores", since(t0));
        t0 = std::chrono::steady_clock::now();
        const OdometryResult again = refine_odometry_.estimate(cur, *target, T_target_cur, staticWeights(scores),
                                                         opt.refine_coarsest_level);
        timings_.add("odometry", since(t0));
        result.iterations = round + 1;
        if (!again.ok) break;
        const bool done = converged(T_target_cur, again.T_cur_ref, opt);
        T_target_cur = again.T_cur_ref;
        if (done) break;
      }
    }
    if (!odo.ok) {
      ++failures_;
      result.tracking_ok = false;
      result.message = odo.message + "; kept the constant-velocity guess";
    }
    result.T_world_cam = orthonormalized(T_world_target * T_target_cur);
    T_prev_cur_velocity_ = prev_->T_world_cam.inverse() * result.T_world_cam;
    velocity_dt_ = depthTime(frame) - depthTime(prev_->frame);
  }

  cv::Mat full_scores;
  if (!scores.empty())
    cv::resize(scores, full_scores, frame.depth.size(), 0, 0, cv::INTER_NEAREST);
  result.dynamic_mask = full_scores.empty() ? cv::Mat(frame.depth.size(), CV_8U, cv::Scalar(0))
                                            : dynamicMask(full_scores, opt.mask_threshold);
  result.scores = scores;
  // trajectory_ holds one pose per frame processed before this one.
  if (map_ && trajectory_.size() % static_cast<size_t>(config_.pipeline.fusion_every) == 0) {
    t0 = std::chrono::steady_clock::now();
    map_->integrate(frame, camera_, result.T_world_cam, full_scores.empty() ? cv::Mat() : staticWeights(full_scores));
    timings_.add("fusion", since(t0));
  }

  // As a target (next frame's previous frame or keyframe), this frame's moving pixels count less.
  const cv::Mat target_weights = scores.empty() ? cv::Mat() : staticWeights(scores);
  setTargetWeights(cur, target_weights);

  if (opt.tracking == "frame_to_keyframe") {
    const SE3 T_kf_cur = keyframe_ ? keyframe_->T_world_cam.inverse() * result.T_world_cam : SE3::Identity();
    if (!keyframe_ || translationNorm(T_kf_cur) > opt.keyframe_translation ||
        rotationAngleDeg(T_kf_cur) > opt.keyframe_rotation_deg || !result.tracking_ok) {
      if (!keyframe_) keyframe_ = std::make_unique<Previous>();
      keyframe_->frame = frame;
      keyframe_->odo = cur;
      keyframe_->T_world_cam = result.T_world_cam;
      keyframe_->from_model = false;
      if (opt.model_keyframes && map_ && map_->size() > 0) {
        t0 = std::chrono::steady_clock::now();
        // The map has no moving objects; the keyframe's image has, so their pixels keep its depth.
        if (auto predicted = modelTarget(*keyframe_, result.dynamic_mask)) {
          keyframe_->odo = std::move(*predicted);
          setTargetWeights(keyframe_->odo, target_weights);
          keyframe_->from_model = true;
        }
        timings_.add("prediction", since(t0));
      }
    }
  }
  if (!prev_) prev_ = std::make_unique<Previous>();
  prev_->frame = frame;
  prev_->odo = std::move(cur);
  prev_->T_world_cam = result.T_world_cam;
  prev_->scores = scores;
  // The geometry dominates the odometry, so the pose found is the camera's at the depth image's
  // time; the trajectory is reported at the colour time, moved there along the last motion.
  SE3 T_world_cam_colour = result.T_world_cam;
  if (opt.shift_to_colour_time && velocity_dt_ > 0) {
    const double s = (frame.timestamp - depthTime(frame)) / velocity_dt_;
    if (std::abs(s) < 1.0) T_world_cam_colour = orthonormalized(result.T_world_cam * expSE3(s * logSE3(T_prev_cur_velocity_)));
  }
  trajectory_.push_back({frame.timestamp, T_world_cam_colour});
  return result;
}

}  // namespace ff
