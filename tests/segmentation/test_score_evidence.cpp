// One test per evidence unit of the dynamic scores (segmentation/score_evidence.h), each with known
// answers on a few clusters laid out in one image row.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>

#include "flowfusion/core/error.h"
#include "flowfusion/segmentation/score_evidence.h"

namespace ff {
namespace {

// Cluster c covers sizes[c] pixels of a 1-row image, in order; -1 pixels (no cluster) at the end.
ClusterGraph clustersInARow(const std::vector<int>& sizes, const std::vector<float>& depths,
                            const std::vector<std::pair<int, int>>& edges = {}, int unlabelled = 0) {
  ClusterGraph g;
  g.num_clusters = static_cast<int>(sizes.size());
  g.sizes = sizes;
  g.mean_depth = depths;
  g.edges = edges;
  g.centroids.resize(sizes.size());
  g.labels = cv::Mat(1, std::accumulate(sizes.begin(), sizes.end(), 0) + unlabelled, CV_32S, cv::Scalar(-1));
  int u = 0;
  for (int c = 0; c < g.num_clusters; ++c)
    for (int k = 0; k < sizes[c]; ++k) g.labels.at<int>(0, u++) = c;
  return g;
}

cv::Mat row(std::initializer_list<float> values) {
  cv::Mat m(1, static_cast<int>(values.size()), CV_32F);
  int u = 0;
  for (const float v : values) m.at<float>(0, u++) = v;
  return m;
}

const float kNaN = std::nanf("");

TEST(ClusterMeans, MeanOfAbsoluteValuesOverValidLabelledPixels) {
  const ClusterGraph g = clustersInARow({2, 3}, {1.f, 1.f}, {}, 1);
  const ClusterMeans m = clusterMeans(g, row({1.f, -3.f, kNaN, 4.f, 2.f, 100.f}), "r");
  EXPECT_DOUBLE_EQ(m.mean(0), 2.0);
  EXPECT_DOUBLE_EQ(m.mean(1), 3.0);  // the NaN pixel is skipped, the unlabelled one too
  EXPECT_EQ(m.count[1], 2);
  const ClusterMeans none = clusterMeans(g, cv::Mat(), "r");
  EXPECT_FALSE(none.has(0));
  EXPECT_TRUE(std::isnan(none.mean(0)));
  EXPECT_THROW(clusterMeans(g, cv::Mat(1, 5, CV_32F, cv::Scalar(0)), "r"), InputError);
  EXPECT_THROW(clusterMeans(g, cv::Mat(1, 6, CV_64F, cv::Scalar(0)), "r"), InputError);
}

TEST(MotionTerms, Eq10WeightsEachMeanAndNormalisesTheDepthTerm) {
  const ClusterGraph g = clustersInARow({2, 2}, {2.f, 0.f});
  ScoreConfig cfg;
  const ClusterMeans r_I = clusterMeans(g, row({0.1f, 0.3f, kNaN, kNaN}), "r_I");
  const ClusterMeans r_D = clusterMeans(g, row({0.4f, 0.4f, 0.5f, 0.5f}), "r_D");
  const ClusterMeans r_F = clusterMeans(g, row({5.f, 5.f, 10.f, 10.f}), "r_F");
  const MotionTerms t = motionTerms(g, r_I, r_D, r_F, cfg);
  EXPECT_NEAR(t.delta[0], cfg.alpha_I * 0.2 + 0.4 / 2.0 + cfg.alpha_F * 5.0, 1e-6);
  EXPECT_NEAR(t.delta[1], cfg.alpha_F * 10.0, 1e-6);  // no r_I; no depth: no depth term
  EXPECT_NEAR(t.flow[0], cfg.alpha_F * 5.0, 1e-6);
  const MotionTerms no_flow = motionTerms(g, r_I, r_D, clusterMeans(g, {}, "r_F"), cfg);
  EXPECT_EQ(no_flow.flow[0], 0.0);
}

TEST(ModelOcclusionTerm, HowFarInFrontOfTheMapOverDepthWeightedByAlphaM) {
  const ClusterGraph g = clustersInARow({2, 1}, {2.f, 1.f});
  ScoreConfig cfg;
  const std::vector<double> m = modelOcclusionTerm(g, clusterMeans(g, row({0.5f, 1.5f, kNaN}), "r_M"), cfg);
  EXPECT_NEAR(m[0], cfg.alpha_M * 1.0 / 2.0, 1e-6);
  EXPECT_EQ(m[1], 0.0);
  cfg.alpha_M = 0;
  EXPECT_EQ(modelOcclusionTerm(g, clusterMeans(g, row({0.5f, 1.5f, 1.f}), "r_M"), cfg)[0], 0.0);
}

TEST(StaticAgreementFactor, ScalesMotionByTheShareNotAgreeing) {
  const ClusterGraph g = clustersInARow({4, 1, 1}, {1.f, 1.f, 1.f});
  ScoreConfig cfg;
  cfg.model_agreement = 0.5;
  const std::vector<double> f = staticAgreementFactor(clusterMeans(g, row({1, 1, 1, 0, 1, kNaN}), "a_M"), cfg);
  EXPECT_NEAR(f[0], 1.0 - 0.5 * 0.75, 1e-12);
  EXPECT_NEAR(f[1], 0.5, 1e-12);
  EXPECT_EQ(f[2], 1.0);  // no agreement measured: no static evidence
}

TEST(ComparedWithNothing, ClustersMostlyOnTheTargetsMoversUnlessTheyAgreeWithTheMap) {
  const ClusterGraph g = clustersInARow({2, 2, 2}, {1.f, 1.f, 1.f});
  ScoreConfig cfg;
  const ClusterMeans on = clusterMeans(g, row({1, 1, 1, 0, 1, 1}), "on_target_mover");
  const ClusterMeans a = clusterMeans(g, row({0, 0, 0, 0, 1, 1}), "a_M");
  const std::vector<char> u = comparedWithNothing(g, on, a, cfg);
  EXPECT_TRUE(u[0]);
  EXPECT_TRUE(u[1]);  // half of its pixels: at target_mover_share 0.5
  EXPECT_FALSE(u[2]);  // it agrees with the map
  cfg.target_mover_share = 0.75;
  EXPECT_FALSE(comparedWithNothing(g, on, a, cfg)[1]);
  cfg.target_mover_share = 0;
  EXPECT_FALSE(comparedWithNothing(g, on, a, cfg)[0]);
}

TEST(BodyEdgeScales, EdgesBetweenClustersAtOneDepthSmoothMore) {
  const ClusterGraph g = clustersInARow({1, 1, 1}, {2.0f, 2.1f, 3.0f}, {{0, 1}, {1, 2}});
  ScoreConfig cfg;
  const std::vector<double> s = bodyEdgeScales(g, cfg);
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0], cfg.body_smoothing);  // 0.1 m apart at 2 m: within body_depth_ratio 0.1
  EXPECT_EQ(s[1], 1.0);
  cfg.body_smoothing = 1.0;
  EXPECT_TRUE(bodyEdgeScales(g, cfg).empty());
}

TEST(GroupMotion, AGroupMovesWithOneMovingClusterAndIsRememberedUnlessItIsTheBackground) {
  // Clusters 0-1 a dynamic group (cluster 0 moves), 2 dynamic alone without motion, 3 static and
  // large so that neither group is the background.
  const ClusterGraph g = clustersInARow({1, 1, 1, 10}, {1.f, 1.f, 1.f, 1.f}, {{0, 1}, {1, 2}, {2, 3}});
  ScoreConfig cfg;
  const Eigen::VectorXd b = (Eigen::VectorXd(4) << 0.9, 0.8, 0.7, 0.1).finished();
  const std::vector<double> delta = {0.25, 0.12, 0.12, 0.0};
  const std::vector<double> flow = {0.2, 0.0, 0.0, 0.0};
  const ClusterMeans memory = clusterMeans(g, row({0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}), "memory");
  GroupMotion m = groupMotion(g, b, delta, flow, memory, false, cfg);
  EXPECT_EQ(m.root[0], m.root[1]);
  EXPECT_EQ(m.root[0], m.root[2]);  // 1 and 2 are both dynamic and touch: one group
  EXPECT_NE(m.root[3], m.root[0]);
  EXPECT_TRUE(m.moves[m.root[0]]);
  EXPECT_TRUE(m.remembered[m.root[0]]);
  EXPECT_TRUE(m.minority[m.root[0]]);

  // Against a map-built target only the flow starts motion: without it, the remembered depth does.
  const std::vector<double> no_flow(4, 0.0);
  m = groupMotion(g, b, delta, no_flow, memory, true, cfg);
  EXPECT_TRUE(m.moves[m.root[0]]);
  const ClusterMeans forgotten = clusterMeans(g, cv::Mat(), "memory");
  m = groupMotion(g, b, delta, no_flow, forgotten, true, cfg);
  EXPECT_FALSE(m.moves[m.root[0]]);
  cfg.model_motion_cue = ModelMotionCue::kAnyTerm;
  EXPECT_TRUE(groupMotion(g, b, delta, no_flow, forgotten, true, cfg).moves[m.root[0]]);

  // A dynamic group over most of the clustered pixels is the background: not remembered.
  const Eigen::VectorXd all = Eigen::VectorXd::Constant(4, 0.9);
  m = groupMotion(g, all, delta, flow, memory, false, cfg);
  EXPECT_FALSE(m.minority[m.root[0]]);
  EXPECT_FALSE(m.remembered[m.root[0]]);
}

TEST(GroupMotion, ClustersAtDifferentDepthsAreSeparateGroups) {
  // A moving person 1.3 m away (cluster 0) touching a black screen's speckles 0.9 m away (cluster
  // 1, dynamic without motion of its own) and a part of the person at 1.35 m (cluster 2).
  const ClusterGraph g = clustersInARow({1, 1, 1, 10}, {1.3f, 0.9f, 1.35f, 2.f}, {{0, 1}, {0, 2}, {1, 3}});
  ScoreConfig cfg;
  const Eigen::VectorXd b = (Eigen::VectorXd(4) << 0.9, 0.8, 0.8, 0.1).finished();
  const std::vector<double> delta = {0.25, 0.12, 0.12, 0.0}, flow = {0.2, 0.0, 0.0, 0.0};
  const ClusterMeans memory = clusterMeans(g, cv::Mat(), "memory");
  GroupMotion m = groupMotion(g, b, delta, flow, memory, false, cfg);
  EXPECT_EQ(m.root[0], m.root[2]);  // 0.05 m at 1.3 m: within group_depth_ratio 0.3
  EXPECT_NE(m.root[0], m.root[1]);  // 0.4 m in front of the person: beyond it
  EXPECT_TRUE(m.moves[m.root[0]]);
  EXPECT_FALSE(m.moves[m.root[1]]);
  cfg.group_depth_ratio = 0;  // any depths: one group, moving with the person
  m = groupMotion(g, b, delta, flow, memory, false, cfg);
  EXPECT_EQ(m.root[0], m.root[1]);
  EXPECT_TRUE(m.moves[m.root[1]]);
}

TEST(LongBaselineTypicalError, ThePairsMedianAboveTheNoiseSettingAndNeverAboveTheFramesError) {
  ScoreConfig c;
  c.flow_error_px = 2.0;
  c.long_baseline_noise_px = 0.5;
  EXPECT_DOUBLE_EQ(longBaselineTypicalErrorPx(c, 0.3), 0.5);   // a quiet pair: the setting
  EXPECT_DOUBLE_EQ(longBaselineTypicalErrorPx(c, 0.8), 0.8);   // a noisier pair: its median
  EXPECT_DOUBLE_EQ(longBaselineTypicalErrorPx(c, 2.0), 2.0);   // the pair scaled to the frame's error
  EXPECT_DOUBLE_EQ(longBaselineTypicalErrorPx(c, std::nan("")), 0.5);  // no finite pair residual
  c.long_baseline_noise_px = 3.0;
  EXPECT_DOUBLE_EQ(longBaselineTypicalErrorPx(c, 0.3), 2.0);   // never above flow_error_px
  c.long_baseline_noise_px = 0;
  EXPECT_DOUBLE_EQ(longBaselineTypicalErrorPx(c, 0.3), 2.0);   // off: the frame's error alone
}

}  // namespace
}  // namespace ff
