// k-means on back-projected 3D points (as StaticFusion / Joint-VO-SF), computed on a
// subsampled pixel grid and propagated to full resolution by a nearest-centroid test among
// the clusters of the neighbouring grid points, which keeps boundaries pixel-accurate at depth
// discontinuities.
#include <algorithm>
#include <cmath>
#include <limits>

#include "flowfusion/core/error.h"
#include "flowfusion/segmentation/cluster_graph_builder.h"

namespace ff {

namespace {

class KMeansClusterer : public Clusterer {
 public:
  explicit KMeansClusterer(const ClusteringConfig& c) : config_(c) {}

  std::string name() const override { return "kmeans"; }

  ClusterGraph cluster(const RgbdFrame& frame, const CameraIntrinsics& camera) override {
    detail::checkClusterInput(frame, camera, "kmeans clustering");
    const cv::Mat& depth = frame.depth;
    const int s = config_.kmeans_subsample;
    const int gw = (depth.cols + s - 1) / s, gh = (depth.rows + s - 1) / s;

    // Grid points: the pixel at the centre of each s x s cell (or -1 without depth).
    std::vector<Eigen::Vector3f> pts;
    cv::Mat grid_idx(gh, gw, CV_32S, cv::Scalar(-1));
    for (int gv = 0; gv < gh; ++gv)
      for (int gu = 0; gu < gw; ++gu) {
        const int u = std::min(gu * s + s / 2, depth.cols - 1), v = std::min(gv * s + s / 2, depth.rows - 1);
        const float z = depth.at<float>(v, u);
        if (!detail::validDepth(z)) continue;
        grid_idx.at<int>(gv, gu) = static_cast<int>(pts.size());
        pts.push_back(camera.backproject(u, v, z).cast<float>());
      }

    cv::Mat labels(depth.size(), CV_32S, cv::Scalar(-1));
    int num_labels = 0;
    if (!pts.empty()) {
      cv::Mat grid_label;
      const std::vector<Eigen::Vector3f> centres = kmeans(pts, grid_idx, grid_label);
      num_labels = static_cast<int>(centres.size());
      propagate(depth, camera, centres, grid_label, labels);
    }
    detail::fillUnlabeled(labels, depth, config_.adjacency_max_rel_depth_jump, num_labels);
    return detail::buildClusterGraph(labels, num_labels, depth, camera, config_.adjacency_max_rel_depth_jump,
                                     config_.adjacency_min_contacts);
  }

 private:
  static constexpr int kWindow = 5;  // grid points, odd

  // Distinct non-negative labels of `grid` within `radius` of (gu, gv), in scan order. seen: one
  // entry per label, an entry equal to `stamp` (a new value per call) marking a label found.
  static int localLabels(const cv::Mat& grid, int gu, int gv, int radius, std::vector<int>& seen, int stamp,
                         int* out) {
    int n = 0;
    for (int b = std::max(0, gv - radius); b <= std::min(grid.rows - 1, gv + radius); ++b) {
      const int* row = grid.ptr<int>(b);
      for (int a = std::max(0, gu - radius); a <= std::min(grid.cols - 1, gu + radius); ++a) {
        const int c = row[a];
        if (c >= 0 && seen[c] != stamp) {
          seen[c] = stamp;
          out[n++] = c;
        }
      }
    }
    return n;
  }

  // Squared distance of c and p in the float operations of Eigen's squaredNorm of c - p
  // (x^2 + (y^2 + z^2)).
  static float squaredDistance(float cx, float cy, float cz, float px, float py, float pz) {
    const float dx = cx - px, dy = cy - py, dz = cz - pz;
    return dx * dx + (dy * dy + dz * dz);
  }

  // The candidate nearest to p, the first of equals.
  static int nearest(const Eigen::Vector3f& p, const std::vector<Eigen::Vector3f>& centres, const int* cand,
                     int ncand) {
    int best = -1;
    float best_d = std::numeric_limits<float>::max();
    for (int k = 0; k < ncand; ++k) {
      const Eigen::Vector3f& c = centres[cand[k]];
      const float d = squaredDistance(c.x(), c.y(), c.z(), p.x(), p.y(), p.z());
      if (d < best_d) {
        best_d = d;
        best = cand[k];
      }
    }
    return best;
  }

  // The centres' coordinates column by column: the distances from a point to all of them are a
  // loop the compiler vectorises (the first Lloyd pass tests every centre for every point).
  struct CentreColumns {
    std::vector<float> x, y, z;
    std::vector<float> distance;  // scratch of nearest()
    explicit CentreColumns(const std::vector<Eigen::Vector3f>& centres) : distance(centres.size()) {
      for (const Eigen::Vector3f& c : centres) {
        x.push_back(c.x());
        y.push_back(c.y());
        z.push_back(c.z());
      }
    }
    // The centre nearest to p, the first of equals (as nearest()).
    int nearest(const Eigen::Vector3f& p) {
      const size_t n = distance.size();
      for (size_t k = 0; k < n; ++k) distance[k] = squaredDistance(x[k], y[k], z[k], p.x(), p.y(), p.z());
      return static_cast<int>(std::min_element(distance.begin(), distance.end()) - distance.begin());
    }
  };

  // Lloyd's algorithm seeded on a regular image grid of about kmeans_clusters cells; empty
  // clusters are dropped. grid_assign: each grid point's cluster (-1 without depth).
  std::vector<Eigen::Vector3f> kmeans(const std::vector<Eigen::Vector3f>& pts, const cv::Mat& grid_idx,
                                      cv::Mat& grid_assign) const {
    const int gw = grid_idx.cols, gh = grid_idx.rows;
    const double aspect = static_cast<double>(gw) / gh;
    const int kx = std::max(1, static_cast<int>(std::lround(std::sqrt(config_.kmeans_clusters * aspect))));
    const int ky = std::max(1, static_cast<int>(std::lround(static_cast<double>(config_.kmeans_clusters) / kx)));
    std::vector<Eigen::Vector3f> centres;
    for (int j = 0; j < ky; ++j)
      for (int i = 0; i < kx; ++i) {
        // First valid grid point found spiralling out from the cell centre, within the cell.
        const int u0 = i * gw / kx, u1 = (i + 1) * gw / kx, v0 = j * gh / ky, v1 = (j + 1) * gh / ky;
        const int cu = (u0 + u1) / 2, cv_ = (v0 + v1) / 2;
        int found = -1;
        for (int r = 0; found < 0 && r <= std::max(u1 - u0, v1 - v0); ++r)
          for (int dv = -r; found < 0 && dv <= r; ++dv)
            for (int du = -r; du <= r; ++du) {
              const int u = cu + du, v = cv_ + dv;
              if (u < u0 || u >= u1 || v < v0 || v >= v1) continue;
              if (grid_idx.at<int>(v, u) >= 0) {
                found = grid_idx.at<int>(v, u);
                break;
              }
            }
        if (found >= 0) centres.push_back(pts[found]);
      }
    if (centres.empty()) centres.push_back(pts[0]);
    std::vector<int> assign(pts.size(), -1);
    grid_assign = cv::Mat(gh, gw, CV_32S, cv::Scalar(-1));
    CentreColumns seeds(centres);
    std::vector<int> seen(centres.size(), -1);
    int stamp = 0;
    for (int it = 0; it < config_.kmeans_iterations; ++it) {
      bool changed = false;
      const cv::Mat prev = grid_assign.clone();
      for (int gv = 0; gv < gh; ++gv)
        for (int gu = 0; gu < gw; ++gu) {
          const int p = grid_idx.at<int>(gv, gu);
          if (p < 0) continue;
          int c;
          if (it == 0) {
            c = seeds.nearest(pts[p]);
          } else {
            // After the global first pass a point can only move to a cluster present around
            // it (as SLIC): ~3x faster than testing all centres, same result in practice.
            int cand[kWindow * kWindow];
            const int ncand = localLabels(prev, gu, gv, kWindow / 2, seen, stamp++, cand);
            c = nearest(pts[p], centres, cand, ncand);
          }
          changed |= c != assign[p];
          assign[p] = c;
          grid_assign.at<int>(gv, gu) = c;
        }
      std::vector<Eigen::Vector3f> sum(centres.size(), Eigen::Vector3f::Zero());
      std::vector<int> cnt(centres.size(), 0);
      for (size_t p = 0; p < pts.size(); ++p) {
        sum[assign[p]] += pts[p];
        ++cnt[assign[p]];
      }
      // Empty clusters are dropped and the survivors renumbered.
      std::vector<int> renum(centres.size(), -1);
      std::vector<Eigen::Vector3f> next;
      for (size_t c = 0; c < centres.size(); ++c)
        if (cnt[c] > 0) {
          renum[c] = static_cast<int>(next.size());
          next.push_back(sum[c] / cnt[c]);
        }
      if (next.size() != centres.size()) {
        for (auto& a : assign) a = renum[a];
        grid_assign.forEach<int>([&](int& a, const int*) {
          if (a >= 0) a = renum[a];
        });
      }
      centres = std::move(next);
      if (!changed) break;
    }
    return centres;
  }

  // Distinct non-negative labels of the 3 x 3 grid points around (gu, gv), in scan order.
  static int cellCandidates(const cv::Mat& grid_label, int gu, int gv, int* cand) {
    int n = 0;
    for (int dv = -1; dv <= 1; ++dv)
      for (int du = -1; du <= 1; ++du) {
        const int a = gu + du, b = gv + dv;
        if (a < 0 || b < 0 || a >= grid_label.cols || b >= grid_label.rows) continue;
        const int c = grid_label.at<int>(b, a);
        if (c >= 0 && std::find(cand, cand + n, c) == cand + n) cand[n++] = c;
      }
    return n;
  }

  // Each pixel's label: the nearest of the clusters of the 3 x 3 grid points around its cell (the
  // first of equals). The points of a row and their distances to a cell's candidates are loops
  // over the pixels that the compiler vectorises (the same float operations as one pixel at a time).
  void propagate(const cv::Mat& depth, const CameraIntrinsics& camera, const std::vector<Eigen::Vector3f>& centres,
                 const cv::Mat& grid_label, cv::Mat& labels) const {
    const int s = config_.kmeans_subsample;
    const float fx = camera.fx, fy = camera.fy, cx = camera.cx, cy = camera.cy;
    const int cols = depth.cols;
    cv::parallel_for_(cv::Range(0, depth.rows), [&](const cv::Range& rows) {
      std::vector<float> px(cols), py(cols), best(s);  // best: squared distance so far per pixel of a cell
      std::vector<int> nearest_label(s);
      for (int v = rows.start; v < rows.end; ++v) {
        const float* z = depth.ptr<float>(v);
        int* l = labels.ptr<int>(v);
        for (int u = 0; u < cols; ++u) {
          px[u] = (u - cx) * z[u] / fx;
          py[u] = (v - cy) * z[u] / fy;
        }
        for (int u0 = 0; u0 < cols; u0 += s) {
          int cand[9];
          const int ncand = cellCandidates(grid_label, u0 / s, v / s, cand);
          if (ncand == 0) continue;
          const int n = std::min(s, cols - u0);
          const float *cell_x = px.data() + u0, *cell_y = py.data() + u0, *cell_z = z + u0;
          float* cell_best = best.data();
          int* cell_label = nearest_label.data();
          std::fill(best.begin(), best.end(), std::numeric_limits<float>::max());
          for (int k = 0; k < ncand; ++k) {
            const float c_x = centres[cand[k]].x(), c_y = centres[cand[k]].y(), c_z = centres[cand[k]].z();
            const int label = cand[k];
            for (int j = 0; j < n; ++j) {  // branch-free, so that it vectorises
              const float d = squaredDistance(c_x, c_y, c_z, cell_x[j], cell_y[j], cell_z[j]);
              const int nearer = -static_cast<int>(d < cell_best[j]);  // all bits set where d is nearer
              cell_label[j] = (label & nearer) | (cell_label[j] & ~nearer);
              cell_best[j] = std::min(cell_best[j], d);
            }
          }
          for (int j = 0; j < n; ++j)
            if (detail::validDepth(cell_z[j])) l[u0 + j] = nearest_label[j];
        }
      }
    });
  }

  ClusteringConfig config_;
};

}  // namespace

std::unique_ptr<Clusterer> makeKMeansClusterer(const ClusteringConfig& config) {
  return std::make_unique<KMeansClusterer>(config);
}

}  // namespace ff
