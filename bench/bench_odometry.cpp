// Micro-benchmark of the dense odometry: one DenseOdometry::estimate with the default settings
// between consecutive 640x480 frames of a noisy synthetic sequence (both rounds of a frame are
// calls like this one), on 1 and 2 OpenCV threads (the first odometry runs beside the flow, where
// OpenCV's nested parallel loops run serially).
//   build-*/bench/flowfusion_microbench --benchmark_filter='Odometry|PixelResiduals'
//     --benchmark_repetitions=5 --benchmark_report_aggregates_only=true   (one command line)
#include <benchmark/benchmark.h>

#include <opencv2/core/utility.hpp>
#include <vector>

#include "flowfusion/odometry/dense_odometry.h"
#include "flowfusion/synth/synthetic_scene.h"

namespace {

const std::vector<ff::OdometryFrame>& frames() {
  static const std::vector<ff::OdometryFrame> prepared = [] {
    ff::synth::SynthConfig config;
    config.frames = 8;
    const ff::synth::SyntheticScene scene(config);
    std::vector<ff::OdometryFrame> out;
    for (int i = 0; i < config.frames; ++i) {
      const ff::RgbdFrame f = scene.render(i).frame;
      out.push_back(ff::prepareOdometryFrame(f.intensity, f.depth, scene.camera(), ff::OdometryConfig{}));
    }
    return out;
  }();
  return prepared;
}

void BM_DenseOdometry(benchmark::State& state) {
  const int threads = cv::getNumThreads();
  cv::setNumThreads(static_cast<int>(state.range(0)));
  const std::vector<ff::OdometryFrame>& f = frames();
  const ff::DenseOdometry odometry;
  size_t i = 1;
  for (auto _ : state) {
    benchmark::DoNotOptimize(odometry.estimate(f[i], f[i - 1]).T_target_source);
    i = i + 1 < f.size() ? i + 1 : 1;
  }
  cv::setNumThreads(threads);
}
BENCHMARK(BM_DenseOdometry)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

// The segmentation's per-pixel residuals at level 1 (one call per score round), with the target's
// depth searched within depth_window_px pixels (0: the bilinear residual only; 4: scores.depth_window_px,
// reached under fast rotation), on 1 OpenCV thread; BM_DenseOdometry/1 is its peer in the same run.
void BM_PixelResiduals(benchmark::State& state) {
  const int threads = cv::getNumThreads();
  cv::setNumThreads(1);
  const std::vector<ff::OdometryFrame>& f = frames();
  const ff::OdometryConfig config;
  const ff::OdometryResult motion = ff::DenseOdometry(config).estimate(f[1], f[0]);
  for (auto _ : state) {
    const ff::PixelResiduals r = ff::computePixelResiduals(f[1], f[0], motion.T_target_source, 1, config, {}, 0,
                                                           static_cast<int>(state.range(0)));
    benchmark::DoNotOptimize(r.abs_depth.data);
  }
  cv::setNumThreads(threads);
}
BENCHMARK(BM_PixelResiduals)->Arg(0)->Arg(4)->Unit(benchmark::kMillisecond);

}  // namespace
