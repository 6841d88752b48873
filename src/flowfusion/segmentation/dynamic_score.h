#pragma once
// Cluster residuals and dynamic scores (NOTES.md steps 4-5, Eqs. 10-15).
#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <utility>
#include <vector>

#include "flowfusion/segmentation/clustering.h"

namespace ff {

struct ScoreConfig {
  // Weights of Eq. 10 (the paper's TUM values, Table III). Units: r_I in intensity units of
  // [0, 1], r_D / D_i dimensionless, r_F in pixels of the 640x480 image.
  double alpha_I = 0.9;
  double alpha_F = 0.022;
  // Residual thresholds of g (Eq. 13): clusters with delta below theta_b are static, above
  // theta_t dynamic. Tuned on the shared static fr1/xyz frames (pairs 0-1, 60-61, ..., 240-241)
  // with ground-truth motion and the default flow and clusters: static cluster deltas have
  // median 0.075, p90 0.15, p99 0.27 (tests/segmentation/test_scores_fr1.cpp); with
  // (0.15, 0.4) about 0.1 % of those pixels score b > 0.5, with (0.1, 0.25) 3 to 8 %. A moving
  // object (~10 px flow residual, 0.1 intensity and 0.1 relative depth change) gives ~0.45.
  double theta_b = 0.15;
  double theta_t = 0.4;
  // Weight of the smoothness term E_G (Eq. 15); 1 = the paper. 0.5 and 2 made no measurable
  // difference on the static fr1 frames above, so the paper's value is kept.
  double lambda_G = 1.0;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(ScoreConfig, alpha_I, alpha_F, theta_b, theta_t, lambda_G)

// Per-pixel residuals of A, CV_32F, same size as the cluster labels; NaN = invalid (skipped).
// An empty image leaves its term out of Eq. 10.
struct ResidualImages {
  cv::Mat r_I;  // |intensity residual|, [0, 1] units
  cv::Mat r_D;  // |depth residual|, metres
  cv::Mat r_F;  // flow residual, pixels
};

struct DynamicScores {
  std::vector<float> delta;  // Eq. 10 per cluster; NaN where the cluster had no valid residual
  std::vector<float> b;      // dynamic score in [0, 1] per cluster
};

// g (Eq. 13) and w (Eq. 14).
double scoreTarget(double delta, double theta_b, double theta_t);
double scoreWeight(double delta, double theta_b, double theta_t);

// delta_i = alpha_I mean(r_I) + mean(r_D) / D_i + alpha_F mean(r_F) over cluster i's pixels
// (Eq. 10 normalised by size; each mean over the pixels where that residual is valid, so one
// missing term does not drop the others), then b from solveScoreEnergy. Throws InputError on
// mismatched sizes/types or invalid thresholds.
DynamicScores computeDynamicScores(const ClusterGraph& graph, const ResidualImages& residuals,
                                   const ScoreConfig& config);

// Minimises E(b) = sum_i w_i (b_i - g_i)^2 + lambda_G sum_{(i,j)} (b_i - b_j)^2 (Eqs. 11-15):
// (W + lambda_G L) b = W g, L the graph Laplacian, solved with a sparse LDLT, then clamped to
// [0, 1]. A NaN delta (no evidence) gets a near-zero data weight towards 0, so its neighbours
// decide its score. Requires theta_t > theta_b, lambda_G >= 0 and edges within range.
Eigen::VectorXd solveScoreEnergy(const std::vector<double>& delta, const std::vector<std::pair<int, int>>& edges,
                                 double theta_b, double theta_t, double lambda_G);

// b per pixel of A (CV_32F), 0 where no cluster.
cv::Mat pixelScores(const ClusterGraph& graph, const DynamicScores& scores);
// 255 where the pixel score exceeds `threshold`, else 0 (CV_8U).
cv::Mat dynamicMask(const cv::Mat& pixel_scores, float threshold = 0.5f);

}  // namespace ff
