#include "flowfusion/segmentation/dynamic_score.h"

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "flowfusion/core/error.h"

namespace ff {

namespace {

// Data weight of a cluster with no valid residual: small enough that any neighbour decides,
// non-zero so that an isolated cluster still has a unique solution (b = 0).
constexpr double kNoEvidenceWeight = 1e-3;

void checkThresholds(double theta_b, double theta_t) {
  if (!(theta_t > theta_b) || !std::isfinite(theta_b) || !std::isfinite(theta_t))
    throw InputError("scores: theta_t (" + std::to_string(theta_t) + ") must be greater than theta_b (" +
                     std::to_string(theta_b) + ")");
}

// Eq. 10's delta per cluster (NaN: no evidence) without and with the model term, and the
// evidence the group decisions read.
struct ClusterDeltas {
  std::vector<double> motion;  // the motion terms times the static agreement factor
  std::vector<double> flow;    // their flow term alone, scaled alike
  std::vector<double> model;   // the model occlusion term
  std::vector<double> full;    // motion + model: the energy's delta
};

ClusterDeltas clusterDeltas(const ClusterGraph& graph, const ResidualImages& residuals, const ScoreConfig& config) {
  const auto [r_I, r_D, r_F, r_M, a_M] = residualMeans(graph, residuals);
  const ClusterMeans on_mover = clusterMeans(graph, residuals.on_target_mover, "on_target_mover");
  MotionTerms terms = motionTerms(graph, r_I, r_D, r_F, config);
  ClusterDeltas d{std::move(terms.delta), std::move(terms.flow), modelOcclusionTerm(graph, r_M, config), {}};
  const std::vector<double> agreement = staticAgreementFactor(a_M, config);
  const std::vector<char> uncompared = comparedWithNothing(graph, on_mover, a_M, config);
  d.full.resize(graph.num_clusters);
  for (int c = 0; c < graph.num_clusters; ++c) {
    d.motion[c] *= agreement[c];
    d.flow[c] *= agreement[c];
    const bool any = r_I.has(c) || r_D.has(c) || r_F.has(c) || r_M.has(c);
    const bool evidence = any && !(uncompared[c] && d.motion[c] + d.model[c] < config.theta_t);
    if (!evidence) d.motion[c] = std::numeric_limits<double>::quiet_NaN();
    d.full[c] = std::isnan(d.motion[c]) ? d.motion[c] : d.motion[c] + d.model[c];
  }
  return d;
}

}  // namespace

ResidualMeans residualMeans(const ClusterGraph& graph, const ResidualImages& residuals) {
  return {clusterMeans(graph, residuals.r_I, "r_I"), clusterMeans(graph, residuals.r_D, "r_D"),
          clusterMeans(graph, residuals.r_F, "r_F"), clusterMeans(graph, residuals.r_M, "r_M"),
          clusterMeans(graph, residuals.a_M, "a_M")};
}

double scoreTarget(double delta, double theta_b, double theta_t) {
  return std::clamp((delta - theta_b) / (theta_t - theta_b), 0.0, 1.0);
}

double scoreWeight(double delta, double theta_b, double theta_t) {
  const double s = (delta - theta_b) / (theta_t - theta_b);
  return std::sqrt(s * s + 1.0);
}

Eigen::VectorXd solveScoreEnergy(const std::vector<double>& delta, const std::vector<std::pair<int, int>>& edges,
                                 double theta_b, double theta_t, double lambda_G,
                                 const std::vector<double>& prior, double lambda_T,
                                 const std::vector<double>& edge_scale) {
  checkThresholds(theta_b, theta_t);
  if (!(lambda_G >= 0) || !std::isfinite(lambda_G))
    throw InputError("scores: lambda_G must be a finite value >= 0, got " + std::to_string(lambda_G));
  for (const double s : edge_scale)
    if (!(s >= 0) || !std::isfinite(s)) throw InputError("scores: edge scales must be finite values >= 0");
  const int n = static_cast<int>(delta.size());
  if (n == 0) return {};
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(n + 4 * edges.size());
  Eigen::VectorXd rhs(n);
  for (int i = 0; i < n; ++i) {
    const bool known = std::isfinite(delta[i]);
    const double w = known ? scoreWeight(delta[i], theta_b, theta_t) : kNoEvidenceWeight;
    const double g = known ? scoreTarget(delta[i], theta_b, theta_t) : 0.0;
    const bool has_prior = lambda_T > 0 && i < static_cast<int>(prior.size()) && std::isfinite(prior[i]);
    triplets.emplace_back(i, i, w + (has_prior ? lambda_T : 0.0));
    rhs[i] = w * g + (has_prior ? lambda_T * prior[i] : 0.0);
  }
  for (size_t e = 0; e < edges.size(); ++e) {
    const auto [i, j] = edges[e];
    if (i < 0 || j < 0 || i >= n || j >= n || i == j)
      throw InputError("scores: edge (" + std::to_string(i) + ", " + std::to_string(j) + ") is invalid for " +
                       std::to_string(n) + " clusters");
    const double l = e < edge_scale.size() ? lambda_G * edge_scale[e] : lambda_G;
    triplets.emplace_back(i, i, l);
    triplets.emplace_back(j, j, l);
    triplets.emplace_back(i, j, -l);
    triplets.emplace_back(j, i, -l);
  }
  Eigen::SparseMatrix<double> A(n, n);
  A.setFromTriplets(triplets.begin(), triplets.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(A);
  // W is positive on the diagonal and L is positive semi-definite, so A is SPD.
  Eigen::VectorXd b = ldlt.solve(rhs);
  return b.cwiseMax(0.0).cwiseMin(1.0);
}

DynamicScores computeDynamicScores(const ClusterGraph& graph, const ResidualImages& residuals,
                                   const ScoreConfig& config) {
  checkThresholds(config.theta_b, config.theta_t);
  const int n = graph.num_clusters;
  if (static_cast<int>(graph.mean_depth.size()) != n || static_cast<int>(graph.sizes.size()) != n)
    throw InputError("scores: cluster graph has " + std::to_string(graph.mean_depth.size()) + " mean depths and " +
                     std::to_string(graph.sizes.size()) + " sizes for " + std::to_string(n) + " clusters");
  ClusterDeltas d = clusterDeltas(graph, residuals, config);
  const ClusterMeans carried = clusterMeans(graph, residuals.prior, "prior");
  const ClusterMeans memory = clusterMeans(graph, residuals.memory, "memory");
  std::vector<double> prior(n);
  for (int c = 0; c < n; ++c) prior[c] = carried.mean(c);
  const std::vector<double> edge_scale = bodyEdgeScales(graph, config);
  const auto solve = [&] {
    return solveScoreEnergy(d.full, graph.edges, config.theta_b, config.theta_t, config.lambda_G, prior,
                            config.temporal_prior, edge_scale);
  };
  Eigen::VectorXd b = solve();
  const GroupMotion groups = groupMotion(graph, b, d.motion, d.flow, memory, residuals.r_D_from_map, config);
  if (config.model_needs_motion && !residuals.r_M.empty()) {
    bool dropped = false;
    for (int c = 0; c < n; ++c) {
      const int r = groups.root[c];
      if (b[c] > kDynamicScore && !groups.moves[r] && !groups.remembered[r] && d.model[c] > 0) {
        d.full[c] = d.motion[c];
        dropped = true;
      }
    }
    if (dropped) b = solve();
  }
  DynamicScores out;
  out.delta.assign(d.full.begin(), d.full.end());
  out.b.assign(b.data(), b.data() + b.size());
  out.moving.resize(n);
  // Motion worth remembering: the group moves now and the cluster was dynamic in the previous
  // frame too (its carried score), so a static surface flagged in one frame is not remembered.
  for (int c = 0; c < n; ++c) {
    const int r = groups.root[c];
    out.moving[c] = b[c] > kDynamicScore && groups.moves[r] && groups.minority[r] && prior[c] > kDynamicScore;
  }
  return out;
}

cv::Mat clusterValues(const ClusterGraph& graph, const std::vector<float>& per_cluster, const char* who) {
  if (static_cast<int>(per_cluster.size()) != graph.num_clusters)
    throw InputError(std::string(who) + ": " + std::to_string(per_cluster.size()) + " values for " +
                     std::to_string(graph.num_clusters) + " clusters");
  cv::Mat out(graph.labels.size(), CV_32FC1);
  for (int v = 0; v < out.rows; ++v) {
    const int* l = graph.labels.ptr<int>(v);
    float* o = out.ptr<float>(v);
    for (int u = 0; u < out.cols; ++u) o[u] = (l[u] >= 0 && l[u] < graph.num_clusters) ? per_cluster[l[u]] : 0.f;
  }
  return out;
}

cv::Mat pixelScores(const ClusterGraph& graph, const DynamicScores& scores) {
  return clusterValues(graph, scores.b, "pixelScores");
}

cv::Mat dynamicMask(const cv::Mat& pixel_scores, float threshold) {
  if (pixel_scores.type() != CV_32FC1) throw InputError("dynamicMask: pixel scores are not CV_32FC1");
  cv::Mat mask;
  cv::compare(pixel_scores, threshold, mask, cv::CMP_GT);
  return mask;
}

}  // namespace ff
