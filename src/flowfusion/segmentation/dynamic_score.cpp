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

void checkResidual(const cv::Mat& r, const cv::Mat& labels, const char* name) {
  if (r.empty()) return;
  if (r.type() != CV_32FC1) throw InputError(std::string("scores: residual ") + name + " is not CV_32FC1");
  if (r.size() != labels.size())
    throw InputError(std::string("scores: residual ") + name + " size differs from the cluster labels");
}

// out(u, v) = compare(z, z_model) where both depths are valid, NaN elsewhere.
template <class Compare>
cv::Mat compareToModel(const cv::Mat& depth, const cv::Mat& model_depth, const char* what, Compare compare) {
  if (depth.type() != CV_32FC1 || model_depth.type() != CV_32FC1 || depth.size() != model_depth.size())
    throw InputError(std::string(what) + ": depth and model depth must be CV_32FC1 of one size");
  const float nan = std::numeric_limits<float>::quiet_NaN();
  cv::Mat out(depth.size(), CV_32FC1);
  for (int v = 0; v < depth.rows; ++v) {
    const float* z = depth.ptr<float>(v);
    const float* zm = model_depth.ptr<float>(v);
    float* o = out.ptr<float>(v);
    for (int u = 0; u < depth.cols; ++u) o[u] = (z[u] > 0 && zm[u] > 0) ? compare(z[u], zm[u]) : nan;
  }
  return out;
}

// Union-find over the adjacency graph joining clusters that both score b > 0.5: each cluster's
// group root (a cluster with b <= 0.5 is its own root).
std::vector<int> dynamicGroups(const std::vector<std::pair<int, int>>& edges, const Eigen::VectorXd& b) {
  std::vector<int> parent(b.size());
  for (size_t c = 0; c < parent.size(); ++c) parent[c] = static_cast<int>(c);
  const auto find = [&](int c) {
    while (parent[c] != c) c = parent[c] = parent[parent[c]];
    return c;
  };
  for (const auto& [i, j] : edges)
    if (b[i] > 0.5 && b[j] > 0.5) parent[find(i)] = find(j);
  for (size_t c = 0; c < parent.size(); ++c) parent[c] = find(static_cast<int>(c));
  return parent;
}

// lambda_G's factor per edge of the graph: body_smoothing where the two clusters' mean depths
// differ by at most body_depth_ratio of the nearer (parts of one body), 1 elsewhere; empty when
// body_smoothing is 1.
std::vector<double> bodyEdgeScales(const ClusterGraph& graph, const ScoreConfig& config) {
  if (config.body_smoothing == 1.0) return {};
  std::vector<double> scale(graph.edges.size(), 1.0);
  for (size_t e = 0; e < graph.edges.size(); ++e) {
    const auto [i, j] = graph.edges[e];
    if (i < 0 || j < 0 || i >= graph.num_clusters || j >= graph.num_clusters) continue;  // the solver rejects it
    const double Di = graph.mean_depth[i], Dj = graph.mean_depth[j];
    if (Di > 0 && Dj > 0 && std::abs(Di - Dj) <= config.body_depth_ratio * std::min(Di, Dj))
      scale[e] = config.body_smoothing;
  }
  return scale;
}

}  // namespace

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

void validate(const ScoreConfig& c) {
  if (!(c.alpha_I >= 0 && std::isfinite(c.alpha_I))) throw InputError("scores.alpha_I must be a finite value >= 0");
  if (!(c.alpha_F >= 0 && std::isfinite(c.alpha_F))) throw InputError("scores.alpha_F must be a finite value >= 0");
  if (!(std::isfinite(c.theta_b) && std::isfinite(c.theta_t) && c.theta_t > c.theta_b))
    throw InputError("scores.theta_t must be greater than scores.theta_b (both finite)");
  if (!(c.lambda_G >= 0 && std::isfinite(c.lambda_G))) throw InputError("scores.lambda_G must be a finite value >= 0");
  if (!(c.alpha_M >= 0 && std::isfinite(c.alpha_M)))
    throw InputError("scores.alpha_M must be a finite value >= 0 (0 turns the model term off)");
  if (!(c.model_margin >= 0 && c.model_margin < 1)) throw InputError("scores.model_margin must be in [0, 1)");
  if (!(c.model_motion_delta >= 0 && std::isfinite(c.model_motion_delta)))
    throw InputError("scores.model_motion_delta must be a finite value >= 0");
  if (!(c.model_agreement >= 0 && c.model_agreement <= 1))
    throw InputError("scores.model_agreement must be in [0, 1] (0 turns the map's static evidence off)");
  if (!(c.agreement_margin > 0 && c.agreement_margin < 1)) throw InputError("scores.agreement_margin must be in (0, 1)");
  if (!(c.agreement_intensity > 0 && c.agreement_intensity <= 1))
    throw InputError("scores.agreement_intensity must be in (0, 1] (1 compares depth alone)");
  if (!(c.temporal_prior >= 0 && std::isfinite(c.temporal_prior)))
    throw InputError("scores.temporal_prior must be a finite value >= 0 (0 turns the prior off)");
  if (!(c.body_smoothing >= 0 && std::isfinite(c.body_smoothing)))
    throw InputError("scores.body_smoothing must be a finite value >= 0 (1 = the paper's uniform lambda_G)");
  if (!(c.body_depth_ratio >= 0 && c.body_depth_ratio < 1)) throw InputError("scores.body_depth_ratio must be in [0, 1)");
  if (!(c.model_memory_s >= 0 && std::isfinite(c.model_memory_s)))
    throw InputError("scores.model_memory_s must be a finite number of seconds >= 0 (0 turns the memory off)");
  if (!(c.target_mover_share >= 0 && c.target_mover_share <= 1))
    throw InputError("scores.target_mover_share must be in [0, 1] (0 turns the rule off)");
  if (!(c.target_mover_margin_px >= 0 && c.target_mover_margin_px <= 16))
    throw InputError("scores.target_mover_margin_px must be in [0, 16] pixels (0 turns the margin off)");
  if (!(c.flow_error_px >= 0 && std::isfinite(c.flow_error_px)))
    throw InputError("scores.flow_error_px must be a finite number of pixels >= 0 (0 turns the scaling off)");
}

DynamicScores computeDynamicScores(const ClusterGraph& graph, const ResidualImages& residuals,
                                   const ScoreConfig& config) {
  checkThresholds(config.theta_b, config.theta_t);
  const cv::Mat& labels = graph.labels;
  if (labels.type() != CV_32SC1) throw InputError("scores: cluster labels are not CV_32SC1");
  checkResidual(residuals.r_I, labels, "r_I");
  checkResidual(residuals.r_D, labels, "r_D");
  checkResidual(residuals.r_F, labels, "r_F");
  checkResidual(residuals.r_M, labels, "r_M");
  checkResidual(residuals.a_M, labels, "a_M");
  checkResidual(residuals.prior, labels, "prior");
  checkResidual(residuals.memory, labels, "memory");
  checkResidual(residuals.on_target_mover, labels, "on_target_mover");
  const int n = graph.num_clusters;
  if (static_cast<int>(graph.mean_depth.size()) != n || static_cast<int>(graph.sizes.size()) != n)
    throw InputError("scores: cluster graph has " + std::to_string(graph.mean_depth.size()) + " mean depths and " +
                     std::to_string(graph.sizes.size()) + " sizes for " + std::to_string(n) + " clusters");

  // Per cluster and term: sum and count of valid pixels.
  constexpr int K = 8;
  constexpr int kFlowTerm = 2;   // index of r_F in `terms`: the motion cue independent of the map
  constexpr int kModelTerm = 3;  // index of r_M in `terms`: kept apart from the motion terms
  constexpr int kAgreement = 4;  // index of a_M: scales the motion terms
  constexpr int kPrior = 5;      // index of the carried scores: the temporal prior
  constexpr int kMemory = 6;     // index of the motion memory: evidence for the model term
  constexpr int kOnMover = 7;    // index of on_target_mover: pixels compared with nothing
  std::vector<double> sum(K * n, 0.0);
  std::vector<int> cnt(K * n, 0);
  const cv::Mat* terms[K] = {&residuals.r_I, &residuals.r_D,  &residuals.r_F,   &residuals.r_M,
                              &residuals.a_M, &residuals.prior, &residuals.memory, &residuals.on_target_mover};
  for (int v = 0; v < labels.rows; ++v) {
    const int* l = labels.ptr<int>(v);
    for (int k = 0; k < K; ++k) {
      if (terms[k]->empty()) continue;
      const float* r = terms[k]->ptr<float>(v);
      for (int u = 0; u < labels.cols; ++u) {
        const int c = l[u];
        if (c < 0 || !std::isfinite(r[u])) continue;
        if (c >= n) throw InputError("scores: label " + std::to_string(c) + " out of range");
        sum[K * c + k] += std::abs(r[u]);
        ++cnt[K * c + k];
      }
    }
  }
  const auto mean = [&](int c, int k) {
    return cnt[K * c + k] > 0 ? sum[K * c + k] / cnt[K * c + k] : std::numeric_limits<double>::quiet_NaN();
  };
  // A cluster landing mostly on the target's own movers has only its flow against the previous
  // frame: a small flow residual there does not show it standing still.
  const auto uncompared = [&](int c) {
    return config.target_mover_share > 0 && sum[K * c + kOnMover] >= config.target_mover_share * graph.sizes[c] &&
           !(mean(c, kAgreement) > 0.5);  // NaN (no agreement term) is not above
  };
  // Eq. 10 from the motion terms (r_I, r_D, r_F) and the model term separately.
  std::vector<double> delta(n), model(n, 0.0), flow_delta(n, 0.0);
  for (int c = 0; c < n; ++c) {
    const double D = graph.mean_depth[c];
    const double inv_D = D > 0 ? 1.0 / D : 0.0;
    const double scale[kModelTerm + 1] = {config.alpha_I, inv_D, config.alpha_F, config.alpha_M * inv_D};
    double d = 0;
    bool any = false;
    for (int k = 0; k <= kModelTerm; ++k) {
      if (cnt[K * c + k] == 0) continue;
      (k == kModelTerm ? model[c] : d) += scale[k] * mean(c, k);
      any = true;
    }
    if (cnt[K * c + kFlowTerm] > 0) flow_delta[c] = config.alpha_F * mean(c, kFlowTerm);
    if (cnt[K * c + kAgreement] > 0) {
      const double static_evidence = std::max(0.0, 1.0 - config.model_agreement * mean(c, kAgreement));
      d *= static_evidence;
      flow_delta[c] *= static_evidence;
    }
    const bool evidence = any && !(uncompared(c) && d + model[c] < config.theta_t);
    delta[c] = evidence ? d : std::numeric_limits<double>::quiet_NaN();
  }
  std::vector<double> prior(n);
  for (int c = 0; c < n; ++c) prior[c] = mean(c, kPrior);
  std::vector<double> full(n);
  for (int c = 0; c < n; ++c) full[c] = std::isnan(delta[c]) ? delta[c] : delta[c] + model[c];
  const std::vector<double> edge_scale = bodyEdgeScales(graph, config);
  const auto solve = [&] {
    return solveScoreEnergy(full, graph.edges, config.theta_b, config.theta_t, config.lambda_G, prior,
                            config.temporal_prior, edge_scale);
  };
  Eigen::VectorXd b = solve();
  // Connected groups of dynamic clusters; which of them move now, which moved recently.
  const std::vector<int> root = dynamicGroups(graph.edges, b);
  std::vector<char> moves(n, 0), flow_moves(n, 0), remembered(n, 0);
  std::vector<double> group_pixels(n, 0.0);
  double pixels = 0;
  for (int c = 0; c < n; ++c) {
    pixels += graph.sizes[c];
    if (b[c] <= 0.5) continue;
    group_pixels[root[c]] += graph.sizes[c];
    if (delta[c] > config.model_motion_delta) moves[root[c]] = 1;
    if (flow_delta[c] > config.model_motion_delta) flow_moves[root[c]] = 1;
    if (mean(c, kMemory) >= 0.5) remembered[root[c]] = 1;
  }
  // A group covering more than half of the clustered pixels is the background under a wrong pose,
  // not a mover that stopped: the memory neither keeps it nor remembers it.
  std::vector<char> minority(n);
  for (int c = 0; c < n; ++c) minority[c] = group_pixels[c] <= 0.5 * pixels;
  for (int c = 0; c < n; ++c) remembered[c] = remembered[c] && minority[c];
  if (config.model_motion_cue == ModelMotionCue::kFlow && residuals.r_D_from_map)
    for (int c = 0; c < n; ++c) moves[c] = flow_moves[c] || (moves[c] && remembered[c]);
  if (config.model_needs_motion && !residuals.r_M.empty()) {
    bool dropped = false;
    for (int c = 0; c < n; ++c)
      if (b[c] > 0.5 && !moves[root[c]] && !remembered[root[c]] && model[c] > 0) {
        full[c] = delta[c];
        dropped = true;
      }
    if (dropped) b = solve();
  }
  DynamicScores out;
  out.delta.assign(full.begin(), full.end());
  out.b.assign(b.data(), b.data() + b.size());
  out.moving.resize(n);
  // Motion worth remembering: the group moves now and the cluster was dynamic in the previous
  // frame too (its carried score), so a static surface flagged in one frame is not remembered.
  for (int c = 0; c < n; ++c) out.moving[c] = b[c] > 0.5 && moves[root[c]] && minority[root[c]] && prior[c] > 0.5;
  return out;
}

cv::Mat modelOcclusion(const cv::Mat& depth, const cv::Mat& model_depth, double margin) {
  const float m = static_cast<float>(margin);
  return compareToModel(depth, model_depth, "modelOcclusion",
                        [m](float z, float zm) { return std::max(0.f, zm - z * (1 + m)); });
}

cv::Mat modelAgreement(const cv::Mat& depth, const cv::Mat& model_depth, double margin, const cv::Mat& intensity,
                       const cv::Mat& model_intensity, double intensity_margin) {
  const float m = static_cast<float>(margin);
  cv::Mat a = compareToModel(depth, model_depth, "modelAgreement",
                             [m](float z, float zm) { return std::abs(zm - z) <= m * z ? 1.f : 0.f; });
  if (intensity.empty() && model_intensity.empty()) return a;
  for (const cv::Mat* i : {&intensity, &model_intensity})
    if (i->type() != CV_32FC1 || i->size() != depth.size())
      throw InputError("modelAgreement: intensity and model intensity must be CV_32FC1 of the depth's size");
  const float mi = static_cast<float>(intensity_margin);
  for (int v = 0; v < a.rows; ++v) {
    const float* I = intensity.ptr<float>(v);
    const float* Im = model_intensity.ptr<float>(v);
    float* o = a.ptr<float>(v);
    for (int u = 0; u < a.cols; ++u)
      if (o[u] == 1.f && std::abs(Im[u] - I[u]) > mi) o[u] = 0.f;
  }
  return a;
}

cv::Mat pixelScores(const ClusterGraph& graph, const DynamicScores& scores) {
  if (static_cast<int>(scores.b.size()) != graph.num_clusters)
    throw InputError("pixelScores: " + std::to_string(scores.b.size()) + " scores for " +
                     std::to_string(graph.num_clusters) + " clusters");
  cv::Mat out(graph.labels.size(), CV_32FC1);
  for (int v = 0; v < out.rows; ++v) {
    const int* l = graph.labels.ptr<int>(v);
    float* o = out.ptr<float>(v);
    for (int u = 0; u < out.cols; ++u) o[u] = (l[u] >= 0 && l[u] < graph.num_clusters) ? scores.b[l[u]] : 0.f;
  }
  return out;
}

cv::Mat dynamicMask(const cv::Mat& pixel_scores, float threshold) {
  if (pixel_scores.type() != CV_32FC1) throw InputError("dynamicMask: pixel scores are not CV_32FC1");
  cv::Mat mask;
  cv::compare(pixel_scores, threshold, mask, cv::CMP_GT);
  return mask;
}

}  // namespace ff
