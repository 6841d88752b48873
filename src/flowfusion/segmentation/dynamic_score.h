#pragma once
// Cluster residuals and dynamic scores (paper Eqs. 10-15; docs/design.md).
#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <utility>
#include <vector>

#include "flowfusion/segmentation/clustering.h"
#include "flowfusion/segmentation/score_config.h"
#include "flowfusion/segmentation/score_evidence.h"

namespace ff {

// Per-pixel residuals of A, CV_32F, same size as the cluster labels; NaN = invalid (skipped).
// An empty image leaves its term out of Eq. 10.
struct ResidualImages {
  cv::Mat r_I;  // |intensity residual|, [0, 1] units
  cv::Mat r_D;  // |depth residual|, metres
  bool r_D_from_map = false;  // r_D compared with a target built from the map (ScoreConfig::model_motion_cue)
  cv::Mat r_F;  // flow residual, pixels
  cv::Mat r_M;  // occlusion of the static model, metres (modelOcclusion)
  cv::Mat a_M;  // agreement with the static model, 1 or 0 (modelAgreement)
  cv::Mat prior;  // previous scores carried into this frame, [0, 1] (ScoreConfig::temporal_prior)
  cv::Mat memory;  // 1 where the pixel moved within model_memory_s, 0 where not (MotionMemory::recall)
  cv::Mat on_target_mover;  // 1 where the pixel lands on the target's own movers, 0 where not
                            // (PixelResiduals::on_target_mover; ScoreConfig::target_mover_share)
};

// The cluster means of the images behind Eq. 10 and the map's terms (clusterMeans).
struct ResidualMeans {
  ClusterMeans r_I, r_D, r_F, r_M, a_M;
};
ResidualMeans residualMeans(const ClusterGraph& graph, const ResidualImages& residuals);

struct DynamicScores {
  std::vector<float> delta;  // Eq. 10 per cluster (with the model term where it was kept); NaN where
                             // the cluster had no valid residual
  std::vector<float> b;      // dynamic score in [0, 1] per cluster
  std::vector<char> moving;  // per cluster: b > 0.5 in a group with motion evidence of this frame
                             // (delta above model_motion_delta, as model_motion_cue allows it; the
                             // memory alone does not count) and a carried prior above 0.5
                             // (dynamic in the previous frame too)
};

// g (Eq. 13) and w (Eq. 14).
double scoreTarget(double delta, double theta_b, double theta_t);
double scoreWeight(double delta, double theta_b, double theta_t);

// Eqs. 10-15 assembled from the evidence units of score_evidence.h: per cluster, delta = the
// motion terms times the static agreement factor, plus the model occlusion term; no evidence (NaN)
// where no residual is valid or where the cluster was compared with nothing and its delta stays
// below theta_t; b from solveScoreEnergy with the carried prior and body smoothing; then the model
// term dropped from the groups that neither move nor are remembered (model_needs_motion) and b
// solved again. Throws InputError on mismatched sizes/types or invalid thresholds.
DynamicScores computeDynamicScores(const ClusterGraph& graph, const ResidualImages& residuals,
                                   const ScoreConfig& config);

// Minimises E(b) = sum_i w_i (b_i - g_i)^2 + lambda_G sum_{(i,j)} s_ij (b_i - b_j)^2 (Eqs. 11-15;
// s_ij the edge's edge_scale, 1 where not given) + lambda_T sum_i (b_i - p_i)^2 over the clusters
// with a finite prior p_i (none when `prior` is empty or lambda_T = 0):
// (W + lambda_T P + lambda_G L) b = W g + lambda_T P p, L the weighted graph Laplacian, P selecting
// the clusters with a prior, solved with a sparse LDLT, then clamped to [0, 1]. A NaN delta (no
// evidence) gets a near-zero data weight towards 0, so its neighbours decide its score. Requires
// theta_t > theta_b, lambda_G >= 0, edge scales >= 0 and edges within range.
Eigen::VectorXd solveScoreEnergy(const std::vector<double>& delta, const std::vector<std::pair<int, int>>& edges,
                                 double theta_b, double theta_t, double lambda_G,
                                 const std::vector<double>& prior = {}, double lambda_T = 0.0,
                                 const std::vector<double>& edge_scale = {});

// Each pixel of A its cluster's entry of `per_cluster` (CV_32F), 0 where no cluster; throws
// InputError when `per_cluster` does not hold one value per cluster (`who` names the caller).
cv::Mat clusterValues(const ClusterGraph& graph, const std::vector<float>& per_cluster, const char* who);
// b per pixel of A (CV_32F), 0 where no cluster.
cv::Mat pixelScores(const ClusterGraph& graph, const DynamicScores& scores);
// 255 where the pixel score exceeds `threshold`, else 0 (CV_8U).
cv::Mat dynamicMask(const cv::Mat& pixel_scores, float threshold = 0.5f);

}  // namespace ff
