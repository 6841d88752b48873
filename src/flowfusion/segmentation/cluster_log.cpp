#include "flowfusion/segmentation/cluster_log.h"

#include <cmath>
#include <cstdio>

#include "flowfusion/core/error.h"
#include "flowfusion/segmentation/score_evidence.h"

namespace ff {
namespace {

// Per cluster: the mean column and row of its pixels.
void centroids(const ClusterGraph& graph, std::vector<ClusterRecord>& records) {
  std::vector<double> su(records.size(), 0.0), sv(records.size(), 0.0);
  for (int v = 0; v < graph.labels.rows; ++v) {
    const int* l = graph.labels.ptr<int>(v);
    for (int u = 0; u < graph.labels.cols; ++u) {
      if (l[u] < 0 || l[u] >= static_cast<int>(records.size())) continue;
      su[l[u]] += u;
      sv[l[u]] += v;
    }
  }
  for (size_t c = 0; c < records.size(); ++c) {
    const double n = graph.sizes[c];
    records[c].u_px = n > 0 ? su[c] / n : std::nan("");
    records[c].v_px = n > 0 ? sv[c] / n : std::nan("");
  }
}

}  // namespace

ClusterLog clusterLog(const ClusterGraph& graph, const ResidualImages& residuals, const DynamicScores& scores) {
  const int n = graph.num_clusters;
  if (static_cast<int>(scores.b.size()) != n || static_cast<int>(scores.delta.size()) != n ||
      static_cast<int>(scores.moving.size()) != n || static_cast<int>(graph.sizes.size()) != n ||
      static_cast<int>(graph.mean_depth.size()) != n)
    throw InputError("clusterLog: scores or cluster sizes do not match the " + std::to_string(n) + " clusters");
  const auto [r_I, r_D, r_F, r_M, a_M] = residualMeans(graph, residuals);
  const ClusterMeans prior = clusterMeans(graph, residuals.prior, "prior");
  const ClusterMeans memory = clusterMeans(graph, residuals.memory, "memory");
  ClusterLog log;
  log.labels = graph.labels;
  log.clusters.resize(n);
  for (int c = 0; c < n; ++c) {
    ClusterRecord& r = log.clusters[c];
    r.pixels = graph.sizes[c];
    r.depth_m = graph.mean_depth[c];
    r.r_I = r_I.mean(c);
    r.r_D_m = r_D.mean(c);
    r.r_F_px = r_F.mean(c);
    r.r_M_m = r_M.mean(c);
    r.a_M = a_M.mean(c);
    r.prior = prior.mean(c);
    r.memory = memory.mean(c);
    r.delta = scores.delta[c];
    r.b = scores.b[c];
    r.moving = scores.moving[c];
  }
  centroids(graph, log.clusters);
  return log;
}

std::string clusterLogCsv(const ClusterLog& log) {
  std::string out = "cluster,pixels,u_px,v_px,depth_m,r_I,r_D_m,r_F_px,r_M_m,a_M,prior,memory,delta,b,moving\n";
  const auto put = [&out](double value, int digits) {
    char text[32];
    std::snprintf(text, sizeof text, "%.*f", digits, value);
    out += ',';
    out += std::isfinite(value) ? text : "nan";
  };
  for (size_t c = 0; c < log.clusters.size(); ++c) {
    const ClusterRecord& r = log.clusters[c];
    out += std::to_string(c) + ',' + std::to_string(r.pixels);
    for (const double value : {r.u_px, r.v_px}) put(value, 1);
    for (const double value : {r.depth_m, r.r_I, r.r_D_m, r.r_F_px, r.r_M_m, r.a_M, r.prior, r.memory, r.delta, r.b})
      put(value, 4);
    out += r.moving ? ",1\n" : ",0\n";
  }
  return out;
}

}  // namespace ff
