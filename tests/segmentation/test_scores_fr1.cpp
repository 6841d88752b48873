// The score thresholds on real data: static fr1/xyz frames, ground-truth motion, so every
// cluster should come out static (the noise floor against which theta_b / theta_t were chosen;
// the choice itself was measured on whole sequences, see ScoreConfig).
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <string>
#include <vector>

#include "flowfusion/flow/flow_residual.h"
#include "flowfusion/io/tum_sequence.h"
#include "flowfusion/segmentation/dynamic_score.h"
#include "testing/test_util.h"

namespace ff {
namespace {

// |I_B(W(x)) - I_A(x)| and |D_B(W(x)) - z_B(x)| (Eqs. 2-3) with the true motion, NaN where the
// warp leaves B or a depth is missing.
void warpResiduals(const RgbdFrame& a, const RgbdFrame& b, const CameraIntrinsics& cam, const SE3& T_b_a,
                   cv::Mat& r_I, cv::Mat& r_D) {
  const float nan = std::nanf("");
  r_I = cv::Mat(a.depth.size(), CV_32F, cv::Scalar(nan));
  r_D = cv::Mat(a.depth.size(), CV_32F, cv::Scalar(nan));
  for (int v = 0; v < a.depth.rows; ++v)
    for (int u = 0; u < a.depth.cols; ++u) {
      const float z = a.depth.at<float>(v, u);
      if (!(z > 0)) continue;
      const Eigen::Vector3d p = T_b_a * cam.backproject(u, v, z);
      if (p.z() <= 0) continue;
      const Eigen::Vector2d x = cam.project(p);
      if (!cam.inImage(x.x(), x.y())) continue;
      const int x0 = std::min(static_cast<int>(x.x()), cam.width - 2), y0 = std::min(static_cast<int>(x.y()), cam.height - 2);
      const float fx = x.x() - x0, fy = x.y() - y0;
      const float ib = (1 - fy) * ((1 - fx) * b.intensity.at<float>(y0, x0) + fx * b.intensity.at<float>(y0, x0 + 1)) +
                       fy * ((1 - fx) * b.intensity.at<float>(y0 + 1, x0) + fx * b.intensity.at<float>(y0 + 1, x0 + 1));
      r_I.at<float>(v, u) = std::abs(ib - a.intensity.at<float>(v, u));
      const float zb = b.depth.at<float>(static_cast<int>(std::lround(x.y())), static_cast<int>(std::lround(x.x())));
      if (zb > 0) r_D.at<float>(v, u) = std::abs(zb - static_cast<float>(p.z()));
    }
}

// A frame at the segmentation level's size: intensity by area, depth by nearest neighbour (not the
// odometry's pyramid, see FlowNoise below).
RgbdFrame atSize(const RgbdFrame& frame, const cv::Size& size) {
  RgbdFrame out;
  cv::resize(frame.intensity, out.intensity, size, 0, 0, cv::INTER_AREA);
  cv::resize(frame.depth, out.depth, size, 0, 0, cv::INTER_NEAREST);
  return out;
}

// Each cluster's mean of r (where it has one) appended to values.
void addClusterMeans(const ClusterGraph& graph, const cv::Mat& r, const char* name, std::vector<float>& values) {
  const ClusterMeans m = clusterMeans(graph, r, name);
  for (int c = 0; c < graph.num_clusters; ++c)
    if (m.has(c)) values.push_back(static_cast<float>(m.mean(c)));
}

// The value at fraction q of the sorted values (0: the smallest, 1: the largest).
float percentile(std::vector<float> v, double q) {
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(q * (v.size() - 1))];
}

TEST(ScoresOnRealData, StaticFr1XyzFramesWithTrueMotionScoreStatic) {
  FF_REQUIRE_SHARED_DATA(dir);
  const TumSequence seq = TumSequence::open(dir);
  ASSERT_TRUE(seq.groundtruth().has_value());
  auto flow = makeOpticalFlow(FlowConfig{});
  auto clusterer = makeClusterer(ClusteringConfig{});
  const ScoreConfig cfg;
  std::vector<float> deltas;
  double dynamic_pixels = 0, pixels = 0;
  for (size_t i = 0; i + 1 < seq.size() && i < 300; i += 60) {
    const RgbdFrame a = seq.load(i), b = seq.load(i + 1);
    SE3 T_w_a, T_w_b;
    ASSERT_TRUE(interpolatePose(*seq.groundtruth(), a.timestamp, T_w_a));
    ASSERT_TRUE(interpolatePose(*seq.groundtruth(), b.timestamp, T_w_b));
    const SE3 T_b_a = T_w_b.inverse() * T_w_a;
    ResidualImages r;
    warpResiduals(a, b, seq.camera(), T_b_a, r.r_I, r.r_D);
    r.r_F = flowResidual(flow->compute(a.intensity, b.intensity), egoFlow(a.depth, seq.camera(), T_b_a));
    const ClusterGraph g = clusterer->cluster(a, seq.camera());
    const DynamicScores s = computeDynamicScores(g, r, cfg);
    for (float d : s.delta)
      if (std::isfinite(d)) deltas.push_back(d);
    const cv::Mat mask = dynamicMask(pixelScores(g, s));
    dynamic_pixels += cv::countNonZero(mask);
    pixels += cv::countNonZero(g.labels >= 0);
  }
  std::cout << "cluster delta on static fr1/xyz: median " << percentile(deltas, 0.5) << ", p90 "
            << percentile(deltas, 0.9) << ", p99 " << percentile(deltas, 0.99) << ", max " << percentile(deltas, 1.0)
            << "; pixels scored dynamic " << dynamic_pixels / pixels << "\n";
  // Measured: median 0.080, p90 0.163, p99 0.28; 1.8 % of pixels scored dynamic with the default
  // (0.1, 0.3) thresholds and alpha_F 0.030 (first measured with DIS fast and the paper's 0.022:
  // median 0.072, 1.6 %; 0.1 % with (0.15, 0.4)): from single frame pairs without the model
  // term, which is what the sequence-level tuning in ScoreConfig trades against. The three
  // terms contribute about equally (median per cluster: intensity 0.02, depth 0.006, flow 0.04),
  // which supports the units of ScoreConfig (r_I in [0, 1], r_F in 640x480 pixels).
  EXPECT_LT(percentile(deltas, 0.5), cfg.theta_b);
  EXPECT_LT(dynamic_pixels / pixels, 0.02);
}

// Each cluster's mean flow residual (pixels of the 640x480 image) over static frame pairs of a
// shared sequence with their true motion, at the pipeline's segmentation level (1; the frames
// downsampled with cv::resize rather than the odometry's pyramid, close enough for a noise floor
// and without linking the odometry here), computed as the pipeline did before issue 29's flow
// changes (DIS fast, Eq. 9) and as it does now (DIS medium, the affine error field taken out, r_F
// no evidence where the flow back misses).
struct FlowNoise {
  std::vector<float> before, now;
};

void addClusterFlowResiduals(const std::string& dir, size_t step, FlowNoise& out) {
  const TumSequence seq = TumSequence::open(dir);
  ASSERT_TRUE(seq.groundtruth().has_value());
  const ScoreConfig scores;
  constexpr int kLevel = 1;                          // the pipeline's segmentation level
  const double level_px = std::ldexp(1.0, kLevel);  // input pixels per pixel of the level
  const CameraIntrinsics seg_camera = seq.camera().atLevel(kLevel);
  FlowConfig fast;
  fast.dis_preset = DisPreset::Fast;
  auto flow_fast = makeOpticalFlow(fast);
  auto flow_now = makeOpticalFlow(FlowConfig{});
  auto clusterer = makeClusterer(ClusteringConfig{});
  for (size_t i = 1; i < seq.size(); i += step) {
    const RgbdFrame prev = seq.load(i - 1), cur = seq.load(i);
    SE3 T_w_prev, T_w_cur;  // frames outside the ground truth's time span are left out
    if (!interpolatePose(*seq.groundtruth(), prev.timestamp, T_w_prev) ||
        !interpolatePose(*seq.groundtruth(), cur.timestamp, T_w_cur))
      continue;
    const cv::Size size(seg_camera.width, seg_camera.height);
    const RgbdFrame seg = atSize(cur, size);
    const ClusterGraph graph = clusterer->cluster(seg, seg_camera);
    const cv::Mat ego = egoFlow(seg.depth, seg_camera, T_w_prev.inverse() * T_w_cur);
    const FlowField before = resizeFlow(flow_fast->compute(cur.intensity, prev.intensity), size);
    const FlowField forward = resizeFlow(flow_now->compute(cur.intensity, prev.intensity), size);
    const FlowField backward = resizeFlow(flow_now->compute(prev.intensity, cur.intensity), size);
    cv::Mat now = flowResidualWithoutAffine(forward, ego, 1.0);
    now.setTo(std::nanf(""), inconsistentFlow(forward, backward, scores.flow_consistency_px / level_px));
    addClusterMeans(graph, flowResidual(before, ego) * level_px, "before", out.before);
    addClusterMeans(graph, now * level_px, "now", out.now);
  }
}

// Why scores.alpha_F is above the paper's 0.022 (docs/tuning.md#alpha_f): the flow residual of
// static clusters fell with the finer flow, its check and its error field, so the same weight
// would leave movers' flow under-weighted against a smaller noise floor. The default puts the
// static clusters' flow term no higher than the paper's weight put it on the residual as it was.
TEST(ScoresOnRealData, StaticClustersFlowTermWithTheDefaultWeightStaysAtThePapersNoiseFloor) {
  FlowNoise noise;
  for (const char* name : {"fr1_xyz_head300", "fr1_rpy_head150"}) {
    const auto dir = testing::sharedTum(name);
    if (!dir) GTEST_SKIP() << testing::sharedDataMissing();
    addClusterFlowResiduals(*dir, 15, noise);
  }
  const double paper_alpha_F = 0.022, alpha_F = ScoreConfig{}.alpha_F;
  for (const double q : {0.5, 0.9, 0.99})
    std::cout << "static clusters' flow term p" << 100 * q << ": before " << paper_alpha_F * percentile(noise.before, q)
              << " (alpha_F " << paper_alpha_F << "), now " << alpha_F * percentile(noise.now, q) << " (alpha_F "
              << alpha_F << ")\n";
  for (const double q : {0.9, 0.99})
    EXPECT_LE(alpha_F * percentile(noise.now, q), paper_alpha_F * percentile(noise.before, q)) << "p" << 100 * q;
  EXPECT_LT(alpha_F * percentile(noise.now, 0.5), ScoreConfig{}.theta_b);
}

// Each cluster's mean flow residual over one frame pair and over the chain of that pair and the
// three before it (ScoreConfig::long_baseline_frames 4), on static fr1/xyz frames with their true
// motion, as the pipeline takes them (the affine error field out, relative to the frame's error, no
// evidence where the flow back misses or the older frame saw something nearer); the chain's as it
// is and as the pipeline scales it (ScoreConfig::long_baseline_noise_px).
struct ChainNoise {
  std::vector<float> pair, chain, scaled;
};

ChainNoise chainFlowResiduals(const std::string& dir, size_t step) {
  const TumSequence seq = TumSequence::open(dir);
  const ScoreConfig scores;
  constexpr int kLevel = 1;  // as in addClusterFlowResiduals
  const double level_px = std::ldexp(1.0, kLevel);
  const CameraIntrinsics seg_camera = seq.camera().atLevel(kLevel);
  const cv::Size size(seg_camera.width, seg_camera.height);
  auto flow = makeOpticalFlow(FlowConfig{});
  auto clusterer = makeClusterer(ClusteringConfig{});
  const int back = scores.long_baseline_frames;
  ChainNoise out;
  for (size_t i = back; i < seq.size(); i += step) {
    std::vector<RgbdFrame> frames, seg;  // [k]: k frames back from i
    std::vector<SE3> T_w(back + 1);
    for (int k = 0; k <= back; ++k) {
      frames.push_back(seq.load(i - k));
      if (!interpolatePose(*seq.groundtruth(), frames[k].timestamp, T_w[k])) return out;
      seg.push_back(atSize(frames[k], size));
    }
    std::vector<FlowField> steps;
    for (int k = 0; k < back; ++k) steps.push_back(resizeFlow(flow->compute(frames[k].intensity, frames[k + 1].intensity), size));
    std::vector<const FlowField*> chain_steps;
    for (const FlowField& f : steps) chain_steps.push_back(&f);
    FlowField chained = chainFlows(chain_steps);
    const SE3 T_past_cur = T_w[back].inverse() * T_w[0];
    chained.uv.setTo(cv::Scalar(std::nanf(""), std::nanf("")),
                     hiddenIn(seg[0].depth, seg[back].depth, seg_camera, T_past_cur, scores.model_margin));
    const auto residual = [&](const FlowField& f, const SE3& T_then_cur) {
      return relativeToFrameError(flowResidualWithoutAffine(f, egoFlow(seg[0].depth, seg_camera, T_then_cur), 1.0) * level_px,
                                  scores.flow_error_px);
    };
    const cv::Mat inconsistent = inconsistentFlow(
        steps[0], resizeFlow(flow->compute(frames[1].intensity, frames[0].intensity), size), scores.flow_consistency_px / level_px);
    cv::Mat pair = residual(steps[0], T_w[1].inverse() * T_w[0]), chain = residual(chained, T_past_cur);
    cv::Mat scaled = relativeToFrameError(chain, longBaselineTypicalErrorPx(scores, finiteMedian(pair)));
    const ClusterGraph graph = clusterer->cluster(seg[0], seg_camera);
    for (auto [r, values] : {std::pair{&pair, &out.pair}, {&chain, &out.chain}, {&scaled, &out.scaled}}) {
      r->setTo(std::nanf(""), inconsistent);
      addClusterMeans(graph, *r, "r_F", *values);
    }
  }
  return out;
}

// Why the long baseline's residual is scaled (ScoreConfig::long_baseline_noise_px,
// docs/tuning.md#long_baseline_noise_px): the chain carries four pairs' errors and the larger of
// the two residuals counts, so as it is the chain's noise alone lifts static clusters above what the
// flow weight was set for.
TEST(ScoresOnRealData, TheLongBaselinesResidualOnStaticClustersIsScaledToThePairsNoise) {
  const auto dir = testing::sharedTum("fr1_xyz_head300");
  if (!dir) GTEST_SKIP() << testing::sharedDataMissing();
  const ChainNoise noise = chainFlowResiduals(*dir, 20);
  ASSERT_GT(noise.pair.size(), 1000u);
  for (const double q : {0.5, 0.9, 0.99})
    std::cout << "static clusters' r_F p" << 100 * q << ": one pair " << percentile(noise.pair, q) << " px, the chain "
              << percentile(noise.chain, q) << " px, scaled "
              << percentile(noise.scaled, q) << " px\n";
  // Measured (every 20th frame; pair / chain / scaled): p50 0.45 / 0.96 / 0.58 px, p90 1.66 / 5.08 /
  // 2.81 px, p99 4.6 / 16.0 / 9.2 px. A tenth of the static clusters would have a flow term above
  // theta_b from the chain's noise alone; scaled, they stay under it.
  const ScoreConfig cfg;
  EXPECT_GT(cfg.alpha_F * percentile(noise.chain, 0.9), cfg.theta_b) << "the cause: the chain as it is";
  EXPECT_LT(cfg.alpha_F * percentile(noise.scaled, 0.9), cfg.theta_b);
}

}  // namespace
}  // namespace ff
