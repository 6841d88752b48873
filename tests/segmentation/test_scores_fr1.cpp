// The score thresholds on real data: static fr1/xyz frames, ground-truth motion, so every
// cluster should come out static (the noise floor against which theta_b / theta_t were chosen;
// the choice itself was measured on whole sequences, see ScoreConfig).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>

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
  std::sort(deltas.begin(), deltas.end());
  auto pct = [&](double q) { return deltas[static_cast<size_t>(q * (deltas.size() - 1))]; };
  std::cout << "cluster delta on static fr1/xyz: median " << pct(0.5) << ", p90 " << pct(0.9) << ", p99 " << pct(0.99)
            << ", max " << deltas.back() << "; pixels scored dynamic " << dynamic_pixels / pixels << "\n";
  // Measured: median 0.072, p90 0.149, p99 0.25; 1.6 % of pixels scored dynamic with the default
  // (0.1, 0.3) thresholds (0.1 % with (0.15, 0.4)): from single frame pairs without the model
  // term, which is what the sequence-level tuning in ScoreConfig trades against. The three
  // terms contribute about equally (median per cluster: intensity 0.02, depth 0.006, flow 0.04),
  // which supports the units of ScoreConfig (r_I in [0, 1], r_F in 640x480 pixels).
  EXPECT_LT(pct(0.5), cfg.theta_b);
  EXPECT_LT(dynamic_pixels / pixels, 0.02);
}

}  // namespace
}  // namespace ff
