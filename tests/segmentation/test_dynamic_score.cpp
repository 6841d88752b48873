#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <random>

#include "../flow/analytic_scene.h"
#include "flowfusion/core/error.h"
#include "flowfusion/segmentation/dynamic_score.h"

namespace ff {
namespace {

TEST(ScoreFunctions, TargetAndWeightAtAndBetweenThresholds) {
  const double tb = 0.1, tt = 0.3;
  EXPECT_DOUBLE_EQ(scoreTarget(0.0, tb, tt), 0.0);
  EXPECT_DOUBLE_EQ(scoreTarget(tb, tb, tt), 0.0);
  EXPECT_NEAR(scoreTarget(0.15, tb, tt), 0.25, 1e-12);
  EXPECT_NEAR(scoreTarget(0.2, tb, tt), 0.5, 1e-12);
  EXPECT_DOUBLE_EQ(scoreTarget(tt, tb, tt), 1.0);
  EXPECT_DOUBLE_EQ(scoreTarget(5.0, tb, tt), 1.0);
  EXPECT_DOUBLE_EQ(scoreWeight(tb, tb, tt), 1.0);
  EXPECT_NEAR(scoreWeight(tt, tb, tt), std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(scoreWeight(0.2, tb, tt), std::sqrt(1.25), 1e-12);
  EXPECT_NEAR(scoreWeight(0.0, tb, tt), std::sqrt(1.25), 1e-12);  // symmetric about theta_b
}

// E(b) written out term by term, independently of the solver's matrix assembly.
double energy(const Eigen::VectorXd& b, const std::vector<double>& delta, const std::vector<std::pair<int, int>>& edges,
              double tb, double tt, double lambda) {
  double e = 0;
  for (size_t i = 0; i < delta.size(); ++i) {
    const double g = std::clamp((delta[i] - tb) / (tt - tb), 0.0, 1.0);
    const double s = (delta[i] - tb) / (tt - tb);
    e += std::sqrt(s * s + 1) * std::pow(b[i] - g, 2);
  }
  for (const auto& [i, j] : edges) e += lambda * std::pow(b[i] - b[j], 2);
  return e;
}

TEST(ScoreEnergy, MatchesDenseReferenceSolve) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(0.0, 0.5);
  const int n = 9;
  std::vector<double> delta(n);
  for (auto& d : delta) d = U(rng);
  const std::vector<std::pair<int, int>> edges = {{0, 1}, {1, 2}, {2, 3}, {0, 3}, {3, 4}, {5, 6}, {6, 7}, {4, 7}, {2, 6}};
  const double tb = 0.12, tt = 0.3;
  for (const double lambda : {0.0, 0.5, 1.0, 4.0}) {
    // E = b^T A b - 2 c^T b + k; recover A and c from energy values at 0, e_i and e_i + e_j.
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(n);
    const double e0 = energy(zero, delta, edges, tb, tt, lambda);
    Eigen::MatrixXd A(n, n);
    Eigen::VectorXd c(n), ei_e(n);
    for (int i = 0; i < n; ++i) ei_e[i] = energy(Eigen::VectorXd::Unit(n, i), delta, edges, tb, tt, lambda);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        if (i == j) continue;
        const double eij = energy(Eigen::VectorXd::Unit(n, i) + Eigen::VectorXd::Unit(n, j), delta, edges, tb, tt, lambda);
        A(i, j) = 0.5 * (eij - ei_e[i] - ei_e[j] + e0);
      }
    for (int i = 0; i < n; ++i) {
      const double e2 = energy(2 * Eigen::VectorXd::Unit(n, i), delta, edges, tb, tt, lambda);
      A(i, i) = 0.5 * (e2 - 2 * ei_e[i] + e0);
      c[i] = -0.5 * (ei_e[i] - e0 - A(i, i));
    }
    const Eigen::VectorXd ref = A.ldlt().solve(c).cwiseMax(0.0).cwiseMin(1.0);
    const Eigen::VectorXd b = solveScoreEnergy(delta, edges, tb, tt, lambda);
    ASSERT_EQ(b.size(), n);
    EXPECT_LT((b - ref).cwiseAbs().maxCoeff(), 1e-9) << "lambda " << lambda;
    // And it is a minimum: no coordinate step lowers E.
    for (int i = 0; i < n; ++i)
      for (const double step : {-1e-3, 1e-3}) {
        Eigen::VectorXd p = b;
        p[i] += step;
        EXPECT_GE(energy(p, delta, edges, tb, tt, lambda), energy(b, delta, edges, tb, tt, lambda) - 1e-12);
      }
  }
}

TEST(ScoreEnergy, NoEvidenceFollowsNeighboursAndBadInputThrows) {
  const double nan = std::nan("");
  const Eigen::VectorXd b = solveScoreEnergy({1.0, nan, 1.0, nan}, {{0, 1}, {1, 2}}, 0.1, 0.3, 1.0);
  EXPECT_NEAR(b[1], 1.0, 1e-3);
  EXPECT_NEAR(b[3], 0.0, 1e-12);  // isolated, no evidence: static
  EXPECT_THROW(solveScoreEnergy({0.1, 0.2}, {{0, 2}}, 0.1, 0.3, 1.0), InputError);
  EXPECT_THROW(solveScoreEnergy({0.1, 0.2}, {{0, 1}}, 0.3, 0.1, 1.0), InputError);
  EXPECT_THROW(solveScoreEnergy({0.1, 0.2}, {{0, 1}}, 0.1, 0.3, -1.0), InputError);
  EXPECT_EQ(solveScoreEnergy({}, {}, 0.1, 0.3, 1.0).size(), 0);
}

TEST(ScoreEnergy, TemporalPriorPullsUndecidedClustersOnly) {
  // No edges: each cluster solves (w + lambda_T) b = w g + lambda_T p on its own.
  const double tb = 0.1, tt = 0.3, lambda_T = 0.5, nan = std::nan("");
  const std::vector<double> delta = {0.2, 0.5, 0.2, 0.05};
  const std::vector<double> prior = {1.0, 0.0, nan, 1.0};
  const Eigen::VectorXd b = solveScoreEnergy(delta, {}, tb, tt, 1.0, prior, lambda_T);
  const auto expected = [&](double d, double p) {
    const double w = scoreWeight(d, tb, tt), g = scoreTarget(d, tb, tt);
    return (w * g + lambda_T * p) / (w + lambda_T);
  };
  EXPECT_NEAR(b[0], expected(0.2, 1.0), 1e-9);  // undecided (g = 0.5): the prior decides it (0.65)
  EXPECT_GT(b[0], 0.6);
  EXPECT_NEAR(b[1], expected(0.5, 0.0), 1e-9);  // clear motion keeps a dynamic score (0.82)
  EXPECT_GT(b[1], 0.8);
  EXPECT_NEAR(b[2], 0.5, 1e-9);                 // no prior where nothing was carried
  EXPECT_NEAR(b[3], expected(0.05, 1.0), 1e-9);
  EXPECT_LT(b[3], 0.5);                         // a static cluster is not kept dynamic by the prior
  // lambda_T = 0 is the paper's energy.
  const Eigen::VectorXd paper = solveScoreEnergy(delta, {}, tb, tt, 1.0, prior, 0.0);
  EXPECT_NEAR(paper[0], 0.5, 1e-9);
}

TEST(DynamicScores, DeltaIsTheSizeNormalisedWeightedResidual) {
  ClusterGraph g;
  g.labels = cv::Mat(2, 4, CV_32S);
  g.labels.setTo(0);
  g.labels(cv::Rect(2, 0, 2, 2)).setTo(1);
  g.labels.at<int>(0, 0) = -1;
  g.num_clusters = 2;
  g.sizes = {3, 4};
  g.mean_depth = {2.0f, 1.0f};
  g.centroids.resize(2);
  ResidualImages r;
  r.r_I = cv::Mat(2, 4, CV_32F, cv::Scalar(0.1f));
  r.r_D = cv::Mat(2, 4, CV_32F, cv::Scalar(0.2f));
  r.r_F = cv::Mat(2, 4, CV_32F, cv::Scalar(2.0f));
  r.r_F.at<float>(1, 1) = std::nanf("");  // skipped: cluster 0's r_F mean is over 2 pixels
  r.r_F.at<float>(0, 1) = 4.0f;
  r.r_I.at<float>(1, 3) = -0.5f;  // absolute values
  ScoreConfig cfg;
  const DynamicScores s = computeDynamicScores(g, r, cfg);
  ASSERT_EQ(s.delta.size(), 2u);
  EXPECT_NEAR(s.delta[0], cfg.alpha_I * 0.1 + 0.2 / 2.0 + cfg.alpha_F * 3.0, 1e-6);
  EXPECT_NEAR(s.delta[1], cfg.alpha_I * 0.2 + 0.2 / 1.0 + cfg.alpha_F * 2.0, 1e-6);

  ResidualImages only_flow;
  only_flow.r_F = r.r_F;
  EXPECT_NEAR(computeDynamicScores(g, only_flow, cfg).delta[1], cfg.alpha_F * 2.0, 1e-6);
  ResidualImages wrong;
  wrong.r_F = cv::Mat(3, 4, CV_32F, cv::Scalar(0));
  EXPECT_THROW(computeDynamicScores(g, wrong, cfg), InputError);
}

TEST(DynamicScores, ObjectClustersScoreHighAndBackgroundLow) {
  const auto scene = testing::AnalyticScene::make(160, 120);
  const auto view = scene.render(SE3::Identity());
  const ClusterGraph g = makeClusterer(ClusteringConfig{})->cluster(view.frame, scene.camera);
  // Residuals as on a moving object (~10 px flow residual, brightness and depth change) and on a
  // well-tracked static background, with noise and invalid pixels.
  cv::Mat noise(view.mask.size(), CV_32F);
  cv::randn(noise, 0, 1);
  ResidualImages r;
  const cv::Mat on = view.mask > 0;
  r.r_F = cv::Mat(view.mask.size(), CV_32F, cv::Scalar(0.4f)) + 0.3 * cv::abs(noise);
  r.r_F.setTo(12.0f, on);
  r.r_I = cv::Mat(view.mask.size(), CV_32F, cv::Scalar(0.02f));
  r.r_I.setTo(0.12f, on);
  r.r_D = cv::Mat(view.mask.size(), CV_32F, cv::Scalar(0.01f));
  r.r_D.setTo(0.15f, on);
  r.r_D(cv::Rect(0, 0, 160, 20)).setTo(std::nanf(""));
  const DynamicScores s = computeDynamicScores(g, r, ScoreConfig{});
  const cv::Mat b = pixelScores(g, s);
  const cv::Mat mask = dynamicMask(b);
  ASSERT_EQ(mask.type(), CV_8UC1);
  int box = 0, box_hit = 0, bg = 0, bg_hit = 0;
  for (int v = 0; v < 120; ++v)
    for (int u = 0; u < 160; ++u) {
      if (view.mask.at<uchar>(v, u)) {
        ++box;
        box_hit += mask.at<uchar>(v, u) == 255;
      } else {
        ++bg;
        bg_hit += mask.at<uchar>(v, u) == 255;
      }
    }
  EXPECT_GT(box_hit, 0.9 * box);
  EXPECT_LT(bg_hit, 0.05 * bg);
  for (int c = 0; c < g.num_clusters; ++c) {
    EXPECT_GE(s.b[c], 0.f);
    EXPECT_LE(s.b[c], 1.f);
  }
}

TEST(ModelOcclusion, OnlySurfacesInFrontOfTheModelCount) {
  const cv::Mat depth = (cv::Mat_<float>(1, 5) << 1.0f, 1.0f, 2.0f, 0.0f, 1.0f);
  const cv::Mat model = (cv::Mat_<float>(1, 5) << 3.0f, 1.02f, 1.5f, 2.0f, 0.0f);
  const cv::Mat r = modelOcclusion(depth, model, 0.03);
  EXPECT_NEAR(r.at<float>(0, 0), 3.0 - 1.03, 1e-6);  // 2 m in front of the background, less the margin
  EXPECT_EQ(r.at<float>(0, 1), 0.f);                 // within the noise margin
  EXPECT_EQ(r.at<float>(0, 2), 0.f);                 // behind the model: a revealed background
  EXPECT_TRUE(std::isnan(r.at<float>(0, 3)));        // no measurement
  EXPECT_TRUE(std::isnan(r.at<float>(0, 4)));        // no model
  EXPECT_THROW(modelOcclusion(depth, cv::Mat(1, 4, CV_32F, cv::Scalar(1)), 0.03), InputError);
}

TEST(ModelAgreement, OnlySurfacesAtTheModelsDepthAgree) {
  const cv::Mat depth = (cv::Mat_<float>(1, 5) << 1.0f, 1.0f, 2.0f, 0.0f, 1.0f);
  const cv::Mat model = (cv::Mat_<float>(1, 5) << 1.005f, 1.05f, 1.9f, 2.0f, 0.0f);
  const cv::Mat a = modelAgreement(depth, model, 0.01);
  EXPECT_EQ(a.at<float>(0, 0), 1.f);           // within 1 % of the depth
  EXPECT_EQ(a.at<float>(0, 1), 0.f);           // 5 cm behind: not the same surface
  EXPECT_EQ(a.at<float>(0, 2), 0.f);           // 10 cm in front
  EXPECT_TRUE(std::isnan(a.at<float>(0, 3)));  // no measurement
  EXPECT_TRUE(std::isnan(a.at<float>(0, 4)));  // no model
  EXPECT_THROW(modelAgreement(depth, cv::Mat(1, 4, CV_32F, cv::Scalar(1)), 0.01), InputError);
}

TEST(ModelAgreement, ATextureSlidingAlongTheModelsSurfaceDisagrees) {
  const cv::Mat depth = (cv::Mat_<float>(1, 3) << 1.0f, 1.0f, 1.0f);
  const cv::Mat model = (cv::Mat_<float>(1, 3) << 1.0f, 1.0f, 1.1f);
  const cv::Mat grey = (cv::Mat_<float>(1, 3) << 0.5f, 0.9f, 0.5f);
  const cv::Mat model_grey = (cv::Mat_<float>(1, 3) << 0.55f, 0.3f, 0.5f);
  const cv::Mat a = modelAgreement(depth, model, 0.01, grey, model_grey, 0.2);
  EXPECT_EQ(a.at<float>(0, 0), 1.f);  // same depth, about the same grey
  EXPECT_EQ(a.at<float>(0, 1), 0.f);  // same depth, another texture
  EXPECT_EQ(a.at<float>(0, 2), 0.f);  // same grey, another depth
  EXPECT_THROW(modelAgreement(depth, model, 0.01, grey, cv::Mat(1, 2, CV_32F, cv::Scalar(0)), 0.2), InputError);
}

TEST(DynamicScores, AgreementWithTheMapScalesTheMotionTerms) {
  // Two lone clusters with the same large flow residual (a static pole's silhouette, say); the
  // first lies where the static map has a surface over three quarters of its pixels.
  ClusterGraph g;
  g.labels = (cv::Mat_<int>(1, 8) << 0, 0, 0, 0, 1, 1, 1, 1);
  g.num_clusters = 2;
  g.sizes = {4, 4};
  g.mean_depth = {1.0f, 1.0f};
  g.centroids.resize(2);
  ResidualImages r;
  r.r_F = cv::Mat(1, 8, CV_32F, cv::Scalar(20.f));
  const float nan = std::numeric_limits<float>::quiet_NaN();
  r.a_M = (cv::Mat_<float>(1, 8) << 1.f, 1.f, 1.f, 0.f, nan, nan, nan, nan);
  ScoreConfig cfg;
  const DynamicScores s = computeDynamicScores(g, r, cfg);
  EXPECT_NEAR(s.delta[1], cfg.alpha_F * 20, 1e-5);         // no map there: Eq. 10 alone
  EXPECT_NEAR(s.delta[0], cfg.alpha_F * 20 * 0.25, 1e-5);  // scaled by 1 - 0.75
  EXPECT_LT(s.b[0], 0.5f);
  EXPECT_GT(s.b[1], 0.5f);
  cfg.model_agreement = 0;
  EXPECT_GT(computeDynamicScores(g, r, cfg).b[0], 0.5f);
}

// Three clusters of two pixels each on one row (labels 0 0 1 1 2 2), at the given mean depths.
ClusterGraph threeClusters(std::vector<float> mean_depth, std::vector<std::pair<int, int>> edges) {
  ClusterGraph g;
  g.labels = (cv::Mat_<int>(1, 6) << 0, 0, 1, 1, 2, 2);
  g.num_clusters = 3;
  g.sizes = {2, 2, 2};
  g.mean_depth = std::move(mean_depth);
  g.centroids.resize(3);
  g.edges = std::move(edges);
  return g;
}

TEST(DynamicScores, ModelTermKeepsOnlyGroupsThatMove) {
  // Clusters 0-1 touch (one object, only cluster 0 shows motion); cluster 2 is alone (a thin
  // static structure the map never fused). All three lie 2 m in front of the model.
  const ClusterGraph g = threeClusters({1.0f, 1.0f, 1.0f}, {{0, 1}});
  ResidualImages r;
  r.r_F = (cv::Mat_<float>(1, 6) << 10.f, 10.f, 0.f, 0.f, 0.f, 0.f);
  r.r_M = cv::Mat(1, 6, CV_32F, cv::Scalar(2.0f));
  ScoreConfig cfg;
  const DynamicScores s = computeDynamicScores(g, r, cfg);
  EXPECT_GT(s.b[0], 0.5f);
  EXPECT_GT(s.b[1], 0.5f);
  EXPECT_LT(s.b[2], 0.5f);
  EXPECT_NEAR(s.delta[2], 0.0, 1e-6);  // its model term was dropped
  cfg.model_needs_motion = false;
  EXPECT_GT(computeDynamicScores(g, r, cfg).b[2], 0.5f);
  cfg.alpha_M = 0;  // the paper's Eq. 10: only the moving cluster's own group member is found
  const DynamicScores paper = computeDynamicScores(g, r, cfg);
  EXPECT_GT(paper.b[0], paper.b[1]);
  EXPECT_LT(paper.b[2], 0.5f);
}

TEST(DynamicScores, WeakMotionDoesNotKeepTheModelTerm) {
  // One cluster 2 m in front of the model whose flow residual gives a delta between theta_b and
  // model_motion_delta: the flow noise of a thin static structure, not the evidence of a moving one.
  ClusterGraph g;
  g.labels = (cv::Mat_<int>(1, 2) << 0, 0);
  g.num_clusters = 1;
  g.sizes = {2};
  g.mean_depth = {1.0f};
  g.centroids.resize(1);
  ScoreConfig cfg;
  const double weak = 0.5 * (cfg.theta_b + cfg.model_motion_delta);
  ResidualImages r;
  r.r_F = cv::Mat(1, 2, CV_32F, cv::Scalar(static_cast<float>(weak / cfg.alpha_F)));
  r.r_M = cv::Mat(1, 2, CV_32F, cv::Scalar(2.0f));
  const DynamicScores s = computeDynamicScores(g, r, cfg);
  EXPECT_NEAR(s.delta[0], weak, 1e-5);  // the model term was dropped
  EXPECT_LT(s.b[0], 0.5f);
  cfg.model_motion_delta = cfg.theta_b;  // any motion above theta_b keeps it
  EXPECT_GT(computeDynamicScores(g, r, cfg).b[0], 0.5f);
}

TEST(DynamicScores, OnlyTheFlowStartsAGroupsMotionTheDepthKeepsARememberedOneMoving) {
  // One cluster 2 m in front of the model with a depth residual (delta 0.17: above
  // model_motion_delta, below theta_t) and no flow residual: a static surface the map and the
  // target lack (real fr1/rpy: a desk come into view), each depth cue confirming the other.
  // Cluster 1 is the static background (the memory holds only a minority of the view).
  ClusterGraph g;
  g.labels = (cv::Mat_<int>(1, 6) << 0, 0, 1, 1, 1, 1);
  g.num_clusters = 2;
  g.sizes = {2, 4};
  g.mean_depth = {1.0f, 1.0f};
  g.centroids.resize(2);
  ResidualImages r;
  r.r_D = (cv::Mat_<float>(1, 6) << 0.17f, 0.17f, 0.f, 0.f, 0.f, 0.f);
  r.r_F = cv::Mat(1, 6, CV_32F, cv::Scalar(0.f));
  r.r_M = (cv::Mat_<float>(1, 6) << 2.f, 2.f, 0.f, 0.f, 0.f, 0.f);
  r.r_D_from_map = true;  // the target is a model keyframe
  ScoreConfig cfg;
  ASSERT_EQ(cfg.model_motion_cue, ModelMotionCue::kFlow);
  const DynamicScores s = computeDynamicScores(g, r, cfg);
  EXPECT_NEAR(s.delta[0], 0.17, 1e-5);  // the model term was dropped
  EXPECT_LT(s.b[0], 0.5f);
  // Remembered as moving (a person who walked there and sat down): the depth keeps it moving.
  r.memory = (cv::Mat_<float>(1, 6) << 1.f, 1.f, 0.f, 0.f, 0.f, 0.f);
  EXPECT_GT(computeDynamicScores(g, r, cfg).b[0], 0.5f);
  // Flow motion alone (delta 0.165, below theta_t without the model term) starts it, no memory.
  r.memory = cv::Mat();
  const cv::Mat r_D = r.r_D;
  r.r_D = cv::Mat();
  r.r_F.colRange(0, 2).setTo(cv::Scalar(static_cast<float>(1.1 * cfg.model_motion_delta / cfg.alpha_F)));
  EXPECT_GT(computeDynamicScores(g, r, cfg).b[0], 0.5f);
  // Against a plain frame the depth residual is the frame's own evidence: any term starts it.
  r.r_D = r_D;
  r.r_F.setTo(cv::Scalar(0.f));
  r.r_D_from_map = false;
  EXPECT_GT(computeDynamicScores(g, r, cfg).b[0], 0.5f);
  // Before: any term started it, whatever the target.
  r.r_D_from_map = true;
  cfg.model_motion_cue = ModelMotionCue::kAnyTerm;
  EXPECT_GT(computeDynamicScores(g, r, cfg).b[0], 0.5f);
}

TEST(DynamicScores, AClusterOnTheTargetsMoversIsDecidedByItsPriorUnlessItMovesOrAgreesWithTheMap) {
  // Four separate clusters, all dynamic in the previous frame but cluster 3. Clusters 0, 2 and 3
  // land on the target's movers (no intensity residual); cluster 1 is compared with the target.
  // Cluster 0 agrees with the map; cluster 3's flow residual shows motion; cluster 2 is the inside
  // of a turning box, whose flow moves little against the previous frame.
  ClusterGraph g;
  g.labels = (cv::Mat_<int>(1, 8) << 0, 0, 1, 1, 2, 2, 3, 3);
  g.num_clusters = 4;
  g.sizes = {2, 2, 2, 2};
  g.mean_depth = {1.0f, 1.0f, 1.0f, 1.0f};
  g.centroids.resize(4);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  ResidualImages r;
  r.r_I = (cv::Mat_<float>(1, 8) << nan, nan, 0.01f, 0.01f, nan, nan, nan, nan);
  r.r_F = (cv::Mat_<float>(1, 8) << 0.5f, 0.5f, 0.5f, 0.5f, 0.5f, 0.5f, 20.f, 20.f);
  r.on_target_mover = (cv::Mat_<float>(1, 8) << 1, 1, 0, 0, 1, 1, 1, 1);
  r.a_M = (cv::Mat_<float>(1, 8) << 1, 1, nan, nan, nan, nan, nan, nan);
  r.prior = (cv::Mat_<float>(1, 8) << 1, 1, 1, 1, 1, 1, nan, nan);
  ScoreConfig cfg;
  const DynamicScores s = computeDynamicScores(g, r, cfg);
  EXPECT_LT(s.b[0], 0.5f);  // the map's agreement is evidence
  EXPECT_LT(s.b[1], 0.5f);  // compared with the target and static
  EXPECT_TRUE(std::isnan(s.delta[2]));
  EXPECT_GT(s.b[2], 0.9f);  // its carried score decides
  EXPECT_GT(s.b[3], 0.9f);  // its motion counts
  cfg.target_mover_share = 0;  // the flow's static claim counts everywhere
  const DynamicScores off = computeDynamicScores(g, r, cfg);
  EXPECT_NEAR(off.delta[2], cfg.alpha_F * 0.5, 1e-6);
  EXPECT_LT(off.b[2], 0.5f);
  r.on_target_mover.at<float>(0, 5) = 0;  // half of cluster 2 compared (its r_I still NaN)
  cfg.target_mover_share = 0.75;
  EXPECT_LT(computeDynamicScores(g, r, cfg).b[2], 0.5f);
  cfg.target_mover_share = 1.5;
  EXPECT_THROW(validate(cfg), InputError);
  cfg.target_mover_share = 0.5;
  cfg.target_mover_margin_px = -1;
  EXPECT_THROW(validate(cfg), InputError);
}

TEST(DynamicScores, BodySmoothingCarriesAMovingPartToItsStillNeighbourAtTheSameDepth) {
  // A walker without a map behind him (no model term): a swinging shin (cluster 1, 2 m, large flow
  // residual), the stance shin beside it (cluster 2, 2.05 m, still), the wall (cluster 0, 4 m),
  // all three adjacent.
  const ClusterGraph g = threeClusters({4.0f, 2.0f, 2.05f}, {{0, 1}, {0, 2}, {1, 2}});
  ResidualImages r;
  r.r_F = (cv::Mat_<float>(1, 6) << 0.f, 0.f, 100.f, 100.f, 0.f, 0.f);
  ScoreConfig cfg;
  cfg.body_smoothing = 2;
  const DynamicScores body = computeDynamicScores(g, r, cfg);
  EXPECT_GT(body.b[1], 0.8f);
  EXPECT_GT(body.b[2], 0.5f);  // the stance shin follows the moving one
  EXPECT_LT(body.b[0], 0.5f);  // the wall does not
  cfg.body_smoothing = 1;      // the paper's uniform smoothing
  const DynamicScores paper = computeDynamicScores(g, r, cfg);
  EXPECT_LT(paper.b[2], 0.5f);
  EXPECT_LT(paper.b[2], body.b[2]);
  cfg.body_smoothing = 2;
  cfg.body_depth_ratio = 0.01;  // 5 cm at 2 m is then a different surface
  EXPECT_NEAR(computeDynamicScores(g, r, cfg).b[2], paper.b[2], 1e-6);
  // In the solver an edge scaled by 2 is that edge counted twice.
  const std::vector<double> delta = {0.0, 2.2, 0.0};
  const Eigen::VectorXd scaled = solveScoreEnergy(delta, {{0, 1}, {1, 2}}, 0.1, 0.3, 1.0, {}, 0.0, {1.0, 2.0});
  const Eigen::VectorXd twice = solveScoreEnergy(delta, {{0, 1}, {1, 2}, {1, 2}}, 0.1, 0.3, 1.0);
  EXPECT_LT((scaled - twice).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_THROW(solveScoreEnergy(delta, {{0, 1}}, 0.1, 0.3, 1.0, {}, 0.0, {-1.0}), InputError);
  cfg.body_smoothing = -1;
  EXPECT_THROW(validate(cfg), InputError);
  cfg.body_smoothing = 2;
  cfg.body_depth_ratio = 1;
  EXPECT_THROW(validate(cfg), InputError);
}

TEST(ScoreConfig, FlowErrorFieldAndConsistencySettingsAreChecked) {
  nlohmann::json j = ScoreConfig{};
  EXPECT_EQ(j["flow_error_field"], "affine_parallax");
  j["flow_error_field"] = "none";
  EXPECT_EQ(j.get<ScoreConfig>().flow_error_field, FlowErrorField::kNone);
  j["flow_error_field"] = "affine";
  EXPECT_EQ(j.get<ScoreConfig>().flow_error_field, FlowErrorField::kAffine);
  j["flow_error_field"] = "quadratic";
  EXPECT_THROW(j.get<ScoreConfig>(), InputError);
  ScoreConfig cfg;
  cfg.flow_consistency_px = 0;  // off
  EXPECT_NO_THROW(validate(cfg));
  for (const double bad : {-1.0, 101.0, std::nan("")}) {
    cfg.flow_consistency_px = bad;
    EXPECT_THROW(validate(cfg), InputError) << bad;
  }
}

}  // namespace
}  // namespace ff
