// Micro-benchmarks of frame preparation: lens undistortion of a 640x480 RGB-D frame as
// TumSequence::load does it for fr1 (colour bilinear, depth nearest), and the PNG decoding before it.
//   build-*/bench/flowfusion_microbench --benchmark_filter='Undistort|DecodeFr1'
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "flowfusion/core/image_file.h"
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

namespace {

// Decoding the first 20 colour and depth PNGs of fr1_xyz_head300 as TumSequence::load reads them
// (readImageFile, our decoder with libdeflate) and through cv::imread, its peer in the same run.
// Skips without the shared data ($FLOWFUSION_SHARED_DATA, default ../shared/data: run it from the
// source folder).
std::vector<std::string> fr1Pngs() {
  const char* env = std::getenv("FLOWFUSION_SHARED_DATA");
  const std::filesystem::path dir = std::filesystem::path(env && *env ? env : "../shared/data") / "tum/fr1_xyz_head300";
  std::vector<std::string> out;
  for (const char* folder : {"rgb", "depth"}) {
    if (!std::filesystem::is_directory(dir / folder)) return {};
    std::vector<std::string> files;
    for (const auto& e : std::filesystem::directory_iterator(dir / folder)) files.push_back(e.path().string());
    std::sort(files.begin(), files.end());
    files.resize(std::min<size_t>(files.size(), 20));
    out.insert(out.end(), files.begin(), files.end());
  }
  return out;
}

void decodeFr1(benchmark::State& state, const std::function<cv::Mat(const std::string&)>& read) {
  const std::vector<std::string> files = fr1Pngs();
  if (files.empty()) {
    state.SkipWithError("shared TUM data not found (set FLOWFUSION_SHARED_DATA)");
    return;
  }
  for (auto _ : state)
    for (const std::string& f : files) benchmark::DoNotOptimize(read(f).data);
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(files.size()));
}

void BM_DecodeFr1ReadImageFile(benchmark::State& state) {
  decodeFr1(state, [](const std::string& f) { return ff::readImageFile(f, cv::IMREAD_UNCHANGED, "image"); });
}
BENCHMARK(BM_DecodeFr1ReadImageFile)->Unit(benchmark::kMillisecond);

void BM_DecodeFr1Imread(benchmark::State& state) {
  decodeFr1(state, [](const std::string& f) { return cv::imread(f, cv::IMREAD_UNCHANGED); });
}
BENCHMARK(BM_DecodeFr1Imread)->Unit(benchmark::kMillisecond);

}  // namespace
