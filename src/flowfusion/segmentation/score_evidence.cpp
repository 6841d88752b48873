#include "flowfusion/segmentation/score_evidence.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "flowfusion/core/error.h"

namespace ff {

namespace {

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

// 1 / D_i, 0 for a cluster without depth.
double inverseDepth(const ClusterGraph& graph, int c) {
  const double D = graph.mean_depth[c];
  return D > 0 ? 1.0 / D : 0.0;
}

// Whether clusters i and j both have a mean depth and those differ by at most `ratio` of the nearer.
bool withinDepthRatio(const ClusterGraph& graph, int i, int j, double ratio) {
  const double Di = graph.mean_depth[i], Dj = graph.mean_depth[j];
  return Di > 0 && Dj > 0 && std::abs(Di - Dj) <= ratio * std::min(Di, Dj);
}

// Union-find over the adjacency graph joining clusters that both score above kDynamicScore and lie
// within depth_ratio of each other's depth (0: at any depths): each cluster's group root (a cluster
// not dynamic is its own root).
std::vector<int> dynamicGroups(const ClusterGraph& graph, const Eigen::VectorXd& b, double depth_ratio) {
  std::vector<int> parent(b.size());
  for (size_t c = 0; c < parent.size(); ++c) parent[c] = static_cast<int>(c);
  const auto find = [&](int c) {
    while (parent[c] != c) c = parent[c] = parent[parent[c]];
    return c;
  };
  for (const auto& [i, j] : graph.edges)
    if (b[i] > kDynamicScore && b[j] > kDynamicScore && (depth_ratio == 0 || withinDepthRatio(graph, i, j, depth_ratio)))
      parent[find(i)] = find(j);
  for (size_t c = 0; c < parent.size(); ++c) parent[c] = find(static_cast<int>(c));
  return parent;
}

}  // namespace

double ClusterMeans::mean(int c) const {
  return count[c] > 0 ? sum[c] / count[c] : std::numeric_limits<double>::quiet_NaN();
}

ClusterMeans clusterMeans(const ClusterGraph& graph, const cv::Mat& image, const char* name) {
  const cv::Mat& labels = graph.labels;
  const int n = graph.num_clusters;
  if (labels.type() != CV_32SC1) throw InputError("scores: cluster labels are not CV_32SC1");
  ClusterMeans out{std::vector<double>(n, 0.0), std::vector<int>(n, 0)};
  if (image.empty()) return out;
  if (image.type() != CV_32FC1) throw InputError(std::string("scores: residual ") + name + " is not CV_32FC1");
  if (image.size() != labels.size())
    throw InputError(std::string("scores: residual ") + name + " size differs from the cluster labels");
  for (int v = 0; v < labels.rows; ++v) {
    const int* l = labels.ptr<int>(v);
    const float* r = image.ptr<float>(v);
    for (int u = 0; u < labels.cols; ++u) {
      const int c = l[u];
      if (c < 0 || !std::isfinite(r[u])) continue;
      if (c >= n) throw InputError("scores: label " + std::to_string(c) + " out of range");
      out.sum[c] += std::abs(r[u]);
      ++out.count[c];
    }
  }
  return out;
}

MotionTerms motionTerms(const ClusterGraph& graph, const ClusterMeans& r_I, const ClusterMeans& r_D,
                        const ClusterMeans& r_F, const ScoreConfig& config) {
  const int n = graph.num_clusters;
  MotionTerms out{std::vector<double>(n, 0.0), std::vector<double>(n, 0.0)};
  for (int c = 0; c < n; ++c) {
    double& d = out.delta[c];
    if (r_I.has(c)) d += config.alpha_I * r_I.mean(c);
    if (r_D.has(c)) d += inverseDepth(graph, c) * r_D.mean(c);
    if (r_F.has(c)) {
      out.flow[c] = config.alpha_F * r_F.mean(c);
      d += out.flow[c];
    }
  }
  return out;
}

std::vector<double> modelOcclusionTerm(const ClusterGraph& graph, const ClusterMeans& r_M, const ScoreConfig& config) {
  std::vector<double> model(graph.num_clusters, 0.0);
  for (int c = 0; c < graph.num_clusters; ++c)
    if (r_M.has(c)) model[c] = config.alpha_M * inverseDepth(graph, c) * r_M.mean(c);
  return model;
}

cv::Mat modelOcclusion(const cv::Mat& depth, const cv::Mat& model_depth, double margin) {
  const float m = static_cast<float>(margin);
  return compareToModel(depth, model_depth, "modelOcclusion",
                        [m](float z, float zm) { return std::max(0.f, zm - z * (1 + m)); });
}

std::vector<double> staticAgreementFactor(const ClusterMeans& a_M, const ScoreConfig& config) {
  std::vector<double> factor(a_M.count.size(), 1.0);
  for (size_t c = 0; c < factor.size(); ++c)
    if (a_M.has(static_cast<int>(c)))
      factor[c] = std::max(0.0, 1.0 - config.model_agreement * a_M.mean(static_cast<int>(c)));
  return factor;
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

std::vector<char> comparedWithNothing(const ClusterGraph& graph, const ClusterMeans& on_target_mover,
                                      const ClusterMeans& a_M, const ScoreConfig& config) {
  std::vector<char> out(graph.num_clusters, 0);
  if (config.target_mover_share <= 0) return out;
  for (int c = 0; c < graph.num_clusters; ++c)
    out[c] = on_target_mover.sum[c] >= config.target_mover_share * graph.sizes[c] &&
             !(a_M.mean(c) > kMostPixels);  // NaN (no agreement term) is not above
  return out;
}

std::vector<double> bodyEdgeScales(const ClusterGraph& graph, const ScoreConfig& config) {
  if (config.body_smoothing == 1.0) return {};
  std::vector<double> scale(graph.edges.size(), 1.0);
  for (size_t e = 0; e < graph.edges.size(); ++e) {
    const auto [i, j] = graph.edges[e];
    if (i < 0 || j < 0 || i >= graph.num_clusters || j >= graph.num_clusters) continue;  // the solver rejects it
    if (withinDepthRatio(graph, i, j, config.body_depth_ratio)) scale[e] = config.body_smoothing;
  }
  return scale;
}

GroupMotion groupMotion(const ClusterGraph& graph, const Eigen::VectorXd& b, const std::vector<double>& delta,
                        const std::vector<double>& flow, const ClusterMeans& memory, bool r_D_from_map,
                        const ScoreConfig& config) {
  const int n = graph.num_clusters;
  GroupMotion g{dynamicGroups(graph, b, config.group_depth_ratio), std::vector<char>(n, 0), std::vector<char>(n, 0),
                std::vector<char>(n, 0)};
  std::vector<char> flow_moves(n, 0);
  std::vector<double> group_pixels(n, 0.0);
  double pixels = 0;
  for (int c = 0; c < n; ++c) {
    pixels += graph.sizes[c];
    if (b[c] <= kDynamicScore) continue;
    const int r = g.root[c];
    group_pixels[r] += graph.sizes[c];
    if (delta[c] > config.model_motion_delta) g.moves[r] = 1;
    if (flow[c] > config.model_motion_delta) flow_moves[r] = 1;
    if (memory.mean(c) >= kMostPixels) g.remembered[r] = 1;
  }
  for (int c = 0; c < n; ++c) {
    g.minority[c] = group_pixels[c] <= kBackgroundShare * pixels;
    g.remembered[c] = g.remembered[c] && g.minority[c];
  }
  if (config.model_motion_cue == ModelMotionCue::kFlow && r_D_from_map)
    for (int c = 0; c < n; ++c) g.moves[c] = flow_moves[c] || (g.moves[c] && g.remembered[c]);
  return g;
}

}  // namespace ff
