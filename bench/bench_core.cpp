// Micro-benchmark of frame preparation: lens undistortion of a 640x480 RGB-D frame as
// TumSequence::load does it for fr1 (colour bilinear, depth nearest).
//   build-*/bench/flowfusion_microbench --benchmark_filter=Undistort
#include <benchmark/benchmark.h>

#include <opencv2/core.hpp>

#include "flowfusion/core/undistortion.h"

namespace {

void BM_UndistortFrame(benchmark::State& state) {
  const ff::CameraIntrinsics cam = *ff::freiburgPreset(1);
  const ff::Undistorter undistorter(cam, *ff::freiburgDistortion(1));
  cv::Mat color(cam.height, cam.width, CV_8UC3), depth(cam.height, cam.width, CV_16UC1);
  cv::randu(color, 0, 255);
  cv::randu(depth, 2500, 15000);
  for (auto _ : state) {
    benchmark::DoNotOptimize(undistorter.undistortColor(color).data);
    benchmark::DoNotOptimize(undistorter.undistortDepth(depth).data);
  }
}
BENCHMARK(BM_UndistortFrame)->Unit(benchmark::kMillisecond);

}  // namespace
