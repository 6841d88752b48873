// Micro-benchmarks of optical flow, flow residuals, clustering and the score solve, with
// accuracy counters measured on the analytic test scene (tests/flow/analytic_scene.h), whose
// true flow is known: static pixels move by egoFlow() of the true depth and motion.
//   build-*/bench/flowfusion_microbench --benchmark_filter='Flow|Cluster|Score|P3P|Ap3p|Carry|MaskEdges'
//     --benchmark_repetitions=5 --benchmark_report_aggregates_only=true   (one command line)
// Counters: epe_px = mean end-point error over static, unoccluded pixels that stay in view;
// straddle = fraction of clusters with >= 10 % of their pixels on each side of the moving
// box's outline; leak = fraction of box pixels in clusters that are < 90 % box.
#include <benchmark/benchmark.h>

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <vector>

#include "../tests/flow/analytic_scene.h"
#include "flowfusion/flow/flow_motion.h"
#include "flowfusion/flow/flow_residual.h"
#include "flowfusion/flow/optical_flow.h"
#include "flowfusion/flow/p3p.h"
#include "flowfusion/segmentation/clustering.h"
#include "flowfusion/segmentation/dynamic_score.h"
#include "flowfusion/segmentation/mask_edges.h"
#include "flowfusion/segmentation/score_carry.h"

namespace {

using ff::testing::AnalyticScene;

struct FlowPair {
  ff::testing::AnalyticView a, b;
  cv::Mat gt;     // CV_32FC2 true flow
  cv::Mat valid;  // CV_8U: unoccluded static pixels that stay in view
};

// A hand-held-like inter-frame motion at 30 Hz (TUM fr1 moves up to ~1.5 cm and ~1.5 deg).
FlowPair makePair(int width, double scale_motion = 1.0) {
  const auto scene = AnalyticScene::make(width, width * 3 / 4);
  ff::Vector6d xi;
  xi << 0.012, -0.006, 0.01, 0.012, -0.018, 0.006;
  const ff::SE3 T_world_b = ff::expSE3(xi * scale_motion);
  FlowPair p{scene.render(ff::SE3::Identity()), scene.render(T_world_b), {}, {}};
  p.gt = ff::egoFlow(p.a.frame.depth, scene.camera, T_world_b.inverse());
  p.valid = cv::Mat(p.gt.size(), CV_8U, cv::Scalar(0));
  const ff::SE3 T_b_a = T_world_b.inverse();
  for (int v = 0; v < p.gt.rows; ++v)
    for (int u = 0; u < p.gt.cols; ++u) {
      const cv::Vec2f f = p.gt.at<cv::Vec2f>(v, u);
      const float ub = u + f[0], vb = v + f[1];
      if (!std::isfinite(ub) || ub < 0 || vb < 0 || ub > p.gt.cols - 1 || vb > p.gt.rows - 1) continue;
      const Eigen::Vector3d pb = T_b_a * scene.camera.backproject(u, v, p.a.frame.depth.at<float>(v, u));
      const float zb = p.b.frame.depth.at<float>(static_cast<int>(std::lround(vb)), static_cast<int>(std::lround(ub)));
      if (std::abs(zb - pb.z()) < 0.02 * pb.z()) p.valid.at<uchar>(v, u) = 255;
    }
  return p;
}

double meanEpe(const cv::Mat& uv, const FlowPair& p) {
  double sum = 0;
  int n = 0;
  for (int v = 0; v < uv.rows; ++v)
    for (int u = 0; u < uv.cols; ++u)
      if (p.valid.at<uchar>(v, u)) {
        const cv::Vec2f d = uv.at<cv::Vec2f>(v, u) - p.gt.at<cv::Vec2f>(v, u);
        sum += std::hypot(d[0], d[1]);
        ++n;
      }
  return sum / std::max(n, 1);
}

void runFlow(benchmark::State& state, const std::string& backend, const std::string& preset) {
  const int width = static_cast<int>(state.range(0));
  ff::FlowConfig c;
  c.backend = ff::enumFromName<ff::FlowBackend>(backend);
  c.dis_preset = ff::enumFromName<ff::DisPreset>(preset);
  c.downscale = static_cast<int>(state.range(1));
  const FlowPair p = makePair(width);
  auto flow = ff::makeOpticalFlow(c);
  ff::FlowField f;
  for (auto _ : state) {
    f = flow->compute(p.a.frame.intensity, p.b.frame.intensity);
    benchmark::DoNotOptimize(f.uv.data);
  }
  state.counters["epe_px"] = meanEpe(f.uv, p);
  // Error in full-resolution (640x480) pixels, the unit alpha_F is tuned for.
  state.counters["epe_640px"] = meanEpe(f.uv, p) * 640.0 / width;
}

void BM_FlowDisUltrafast(benchmark::State& s) { runFlow(s, "dis", "ultrafast"); }
void BM_FlowDisFast(benchmark::State& s) { runFlow(s, "dis", "fast"); }
void BM_FlowDisMedium(benchmark::State& s) { runFlow(s, "dis", "medium"); }
void BM_FlowFarneback(benchmark::State& s) { runFlow(s, "farneback", "fast"); }
// Args: image width (4:3), downscale.
#define FLOW_ARGS ArgsProduct({{640, 320}, {1, 2, 4}})->Unit(benchmark::kMillisecond)
BENCHMARK(BM_FlowDisUltrafast)->FLOW_ARGS;
BENCHMARK(BM_FlowDisFast)->FLOW_ARGS;
BENCHMARK(BM_FlowDisMedium)->FLOW_ARGS;
BENCHMARK(BM_FlowFarneback)->FLOW_ARGS;

void BM_EgoFlowAndResidual(benchmark::State& state) {
  const FlowPair p = makePair(static_cast<int>(state.range(0)));
  const auto scene = AnalyticScene::make(p.gt.cols, p.gt.rows);
  const ff::FlowField f{p.gt};
  for (auto _ : state) {
    const cv::Mat r = ff::flowResidual(f, ff::egoFlow(p.a.frame.depth, scene.camera, ff::SE3::Identity()));
    benchmark::DoNotOptimize(r.data);
  }
}
BENCHMARK(BM_EgoFlowAndResidual)->Arg(640)->Arg(320)->Unit(benchmark::kMillisecond);

// The previous frame's scores carried into the current one (score_carry.h; three calls a frame at
// the segmentation level, 320x240): a splat per pixel, against BM_EgoFlowAndResidual/320, which
// projects the same pixels once, as its peer in the same run.
void BM_CarryScores(benchmark::State& state) {
  const int width = static_cast<int>(state.range(0));
  const FlowPair p = makePair(width);
  const auto scene = AnalyticScene::make(width, width * 3 / 4);
  cv::Mat scores(p.a.frame.depth.size(), CV_32F);
  cv::randu(scores, 0.0, 1.0);
  ff::Vector6d xi;
  xi << 0.01, -0.005, 0.008, 0.01, 0.015, -0.005;  // a hand-held motion at 30 Hz (m, rad)
  const ff::SE3 T_cur_prev = ff::expSE3(xi);
  for (auto _ : state) {
    const cv::Mat carried = ff::carryScores(scores, p.a.frame.depth, scene.camera, T_cur_prev, 0.f);
    benchmark::DoNotOptimize(carried.data);
  }
}
BENCHMARK(BM_CarryScores)->Arg(640)->Arg(320)->Unit(benchmark::kMillisecond);

// The written mask's edge refined at the input's resolution (mask_edges.h; once a frame at 640x480):
// the box's mask as the half-size scores give it, shifted by two pixels, against BM_CarryScores/640.
void BM_RefineMaskEdges(benchmark::State& state) {
  const int width = static_cast<int>(state.range(0));
  const FlowPair p = makePair(width);
  cv::Mat shifted;
  const cv::Mat shift = (cv::Mat_<double>(2, 3) << 1, 0, 2, 0, 1, 0);
  cv::warpAffine(p.a.mask, shifted, shift, p.a.mask.size(), cv::INTER_NEAREST);
  for (auto _ : state) {
    cv::Mat mask = shifted.clone();
    ff::refineMaskEdges(mask, p.a.frame.depth, p.a.frame.color, 2);
    benchmark::DoNotOptimize(mask.data);
  }
}
BENCHMARK(BM_RefineMaskEdges)->Arg(640)->Unit(benchmark::kMillisecond);

void runCluster(benchmark::State& state, const std::string& backend) {
  const int width = static_cast<int>(state.range(0));
  auto scene = AnalyticScene::make(width, width * 3 / 4);
  // Second argument 1: a flat box (10 cm deep) against the wall, so its outline is only a
  // 3 % depth step: the hard case of a person close to a wall.
  if (state.range(1) == 1) {
    scene.box_half.z() = 0.05;
    scene.box_centre.z() = scene.wall_z - scene.box_half.z();
  }
  const auto view = scene.render(ff::SE3::Identity());
  ff::ClusteringConfig c;
  c.backend = ff::enumFromName<ff::ClusteringBackend>(backend);
  if (state.range(2) > 0) c.kmeans_clusters = static_cast<int>(state.range(2));
  auto clusterer = ff::makeClusterer(c);
  ff::ClusterGraph g;
  for (auto _ : state) {
    g = clusterer->cluster(view.frame, scene.camera);
    benchmark::DoNotOptimize(g.labels.data);
  }
  std::vector<int> inside(g.num_clusters, 0);
  int box = 0;
  for (int v = 0; v < g.labels.rows; ++v)
    for (int u = 0; u < g.labels.cols; ++u)
      if (view.mask.at<uchar>(v, u)) {
        ++inside[g.labels.at<int>(v, u)];
        ++box;
      }
  int straddle = 0, leaked = 0;
  for (int i = 0; i < g.num_clusters; ++i) {
    const double frac = static_cast<double>(inside[i]) / g.sizes[i];
    straddle += frac >= 0.1 && frac <= 0.9;
    if (frac < 0.9) leaked += inside[i];
  }
  state.counters["clusters"] = g.num_clusters;
  state.counters["edges"] = static_cast<double>(g.edges.size());
  state.counters["straddle"] = static_cast<double>(straddle) / std::max(g.num_clusters, 1);
  state.counters["leak"] = static_cast<double>(leaked) / std::max(box, 1);
}
void BM_ClusterKMeans(benchmark::State& s) { runCluster(s, "kmeans"); }
void BM_ClusterSupervoxel(benchmark::State& s) { runCluster(s, "supervoxel"); }
// Args: image width (4:3), flat box against the wall (1) or 1.3 m in front of it (0), number
// of k-means clusters (0: the default).
BENCHMARK(BM_ClusterKMeans)->ArgsProduct({{640, 320}, {0, 1}, {0, 48, 192}})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ClusterSupervoxel)->ArgsProduct({{640, 320}, {0, 1}, {0}})->Unit(benchmark::kMillisecond);

void BM_ScoreSolve(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(0.0, 0.4);
  std::vector<double> delta(n);
  for (auto& d : delta) d = U(rng);
  std::vector<std::pair<int, int>> edges;
  for (int i = 0; i < n; ++i)
    for (int k = 1; k <= 3; ++k)
      if (i + k < n) edges.emplace_back(i, i + k);
  for (auto _ : state) benchmark::DoNotOptimize(ff::solveScoreEnergy(delta, edges, 0.1, 0.25, 1.0).data());
}
BENCHMARK(BM_ScoreSolve)->Arg(96)->Arg(1000)->Unit(benchmark::kMicrosecond);

// The flow split's minimal hypotheses: 256 four-correspondence draws of a hand-held-like motion
// (points at 0.5-5 m over the image, 0.5 px of pixel noise), solved in turn; time per draw.
struct FourPointDraw {
  std::array<Eigen::Vector3d, 4> points_a;
  std::array<Eigen::Vector2d, 4> pixels_b;
  std::vector<cv::Point3f> object;
  std::vector<cv::Point2f> image;
};

std::vector<FourPointDraw> fourPointDraws(const ff::CameraIntrinsics& cam) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0, cam.width - 1), v(0, cam.height - 1), z(0.5, 5);
  std::normal_distribution<double> noise(0, 0.5);
  ff::Vector6d xi;
  xi << 0.012, -0.006, 0.01, 0.012, -0.018, 0.006;
  const ff::SE3 T_b_a = ff::expSE3(xi);
  std::vector<FourPointDraw> draws(256);
  for (FourPointDraw& d : draws)
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector2d px(u(rng), v(rng));
      // Float coordinates, as FlowCorrespondences holds them.
      const Eigen::Vector3f p = (T_b_a.inverse() * cam.backproject(px.x(), px.y(), z(rng))).cast<float>();
      const Eigen::Vector2f q = (px + Eigen::Vector2d(noise(rng), noise(rng))).cast<float>();
      d.points_a[k] = p.cast<double>();
      d.pixels_b[k] = q.cast<double>();
      d.object.emplace_back(p.x(), p.y(), p.z());
      d.image.emplace_back(q.x(), q.y());
    }
  return draws;
}

void BM_P3PChoosingByFourth(benchmark::State& state) {
  const ff::CameraIntrinsics cam = *ff::freiburgPreset(1);
  const std::vector<FourPointDraw> draws = fourPointDraws(cam);
  size_t i = 0;
  for (auto _ : state) {
    const FourPointDraw& d = draws[i++ % draws.size()];
    benchmark::DoNotOptimize(ff::solveP3PChoosingByFourth(d.points_a, d.pixels_b, cam));
  }
}
BENCHMARK(BM_P3PChoosingByFourth)->Unit(benchmark::kMicrosecond);

// What the split called before: cv::solvePnP(SOLVEPNP_AP3P) on the same draws (as float points).
void BM_SolvePnPAp3p(benchmark::State& state) {
  const ff::CameraIntrinsics cam = *ff::freiburgPreset(1);
  const std::vector<FourPointDraw> draws = fourPointDraws(cam);
  cv::Mat K;
  cv::eigen2cv(cam.K(), K);
  size_t i = 0;
  for (auto _ : state) {
    const FourPointDraw& d = draws[i++ % draws.size()];
    cv::Mat rvec, tvec;
    benchmark::DoNotOptimize(cv::solvePnP(d.object, d.image, K, cv::noArray(), rvec, tvec, false, cv::SOLVEPNP_AP3P));
  }
}
BENCHMARK(BM_SolvePnPAp3p)->Unit(benchmark::kMicrosecond);

// The whole flow split (consensus stage) on 1000 correspondences over the image (0.5-5 m): 70 %
// moved with the camera, 30 % with a mover, 0.5 px of pixel noise; its default 200 hypotheses.
void BM_FlowSplit(benchmark::State& state) {
  const ff::CameraIntrinsics cam = *ff::freiburgPreset(1);
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> u(0, cam.width - 1), v(0, cam.height - 1), z(0.5, 5), share(0, 1);
  std::normal_distribution<double> noise(0, 0.5);
  ff::Vector6d xi_camera, xi_mover;
  xi_camera << 0.012, -0.006, 0.01, 0.012, -0.018, 0.006;
  xi_mover << 0.05, 0.0, -0.03, 0.0, 0.04, 0.0;
  const ff::SE3 T_b_a = ff::expSE3(xi_camera).inverse(), T_b_a_mover = T_b_a * ff::expSE3(xi_mover);
  ff::FlowCorrespondences c;
  while (c.size() < 1000) {
    const Eigen::Vector3d p = cam.backproject(u(rng), v(rng), z(rng));
    const Eigen::Vector3d q = (share(rng) < 0.7 ? T_b_a : T_b_a_mover) * p;
    const Eigen::Vector2d px = cam.project(q) + Eigen::Vector2d(noise(rng), noise(rng));
    if (q.z() <= 0 || !cam.inImage(px.x(), px.y())) continue;
    c.points_a.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
    c.pixels_b.emplace_back(static_cast<float>(px.x()), static_cast<float>(px.y()));
  }
  for (auto _ : state) benchmark::DoNotOptimize(ff::splitFlowMotions(c, cam, ff::ConsensusConfig{}).ok);
}
BENCHMARK(BM_FlowSplit)->Unit(benchmark::kMillisecond);

}  // namespace
