// Micro-benchmarks of the static map (issue 5): fusion and model prediction per 640x480 frame of a
// noisy synthetic sequence with two moving objects (ground-truth masks as weights), and Open3D's
// legacy ScalableTSDFVolume integration of the same frames as the alternative that was measured.
//   build-*/bench/flowfusion_microbench --benchmark_filter='Surfel|Tsdf'
//     --benchmark_repetitions=5 --benchmark_report_aggregates_only=true   (one command line)
// Counters: surfels = map size at the end of the run.
#include <benchmark/benchmark.h>

#include <open3d/geometry/Image.h>
#include <open3d/geometry/RGBDImage.h>
#include <open3d/pipelines/integration/ScalableTSDFVolume.h>

#include <vector>

#include "flowfusion/fusion/static_map.h"
#include "flowfusion/synth/synthetic_scene.h"

namespace {

struct Sequence {
  ff::CameraIntrinsics camera;
  std::vector<ff::synth::SynthFrame> frames;
  std::vector<cv::Mat> weights;  // 1 - mask
};

const Sequence& sequence() {
  static const Sequence seq = [] {
    ff::synth::SynthConfig config;
    config.frames = 60;
    config.objects = 2;
    const ff::synth::SyntheticScene scene(config);
    Sequence s;
    s.camera = scene.camera();
    for (int i = 0; i < config.frames; ++i) {
      s.frames.push_back(scene.render(i));
      cv::Mat w;
      s.frames.back().mask.convertTo(w, CV_32F, -1.0 / 255.0, 1.0);
      s.weights.push_back(w);
    }
    return s;
  }();
  return seq;
}

// A map that has seen the whole sequence once, so the timed loop runs at its steady size.
ff::StaticMap warmMap(const Sequence& seq) {
  ff::StaticMap map;
  for (size_t i = 0; i < seq.frames.size(); ++i)
    map.integrate(seq.frames[i].frame, seq.camera, seq.frames[i].T_world_cam, seq.weights[i]);
  return map;
}

void BM_SurfelIntegrate(benchmark::State& state) {
  const Sequence& seq = sequence();
  ff::StaticMap map = warmMap(seq);
  size_t i = 0;
  for (auto _ : state) {
    const auto& f = seq.frames[i % seq.frames.size()];
    map.integrate(f.frame, seq.camera, f.T_world_cam, seq.weights[i % seq.frames.size()]);
    ++i;
  }
  state.counters["surfels"] = static_cast<double>(map.size());
}
BENCHMARK(BM_SurfelIntegrate)->Unit(benchmark::kMillisecond);

// Renders the warm map at the sequence's poses in turn with render(map, T_world_cam, camera).
// Argument: pyramid level of the rendered image (0: 640x480, 1: 320x240).
template <class Render>
void benchRender(benchmark::State& state, Render&& render) {
  const Sequence& seq = sequence();
  const ff::StaticMap map = warmMap(seq);
  const ff::CameraIntrinsics camera = seq.camera.atLevel(static_cast<int>(state.range(0)));
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(render(map, seq.frames[i % seq.frames.size()].T_world_cam, camera));
    ++i;
  }
  state.counters["surfels"] = static_cast<double>(map.size());
}

void BM_SurfelPredict(benchmark::State& state) {
  benchRender(state, [](const ff::StaticMap& m, const ff::SE3& T, const ff::CameraIntrinsics& c) {
    return m.predict(T, c);
  });
}
BENCHMARK(BM_SurfelPredict)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// predict()'s averaged depth alone from square splats (the tracking targets).
void BM_SurfelPredictDepth(benchmark::State& state) {
  benchRender(state, [](const ff::StaticMap& m, const ff::SE3& T, const ff::CameraIntrinsics& c) {
    return m.predictDepth(T, c);
  });
}
BENCHMARK(BM_SurfelPredictDepth)->Arg(1)->Unit(benchmark::kMillisecond);

// The segmentation's view of the map (stable surfels, square splats).
void BM_SurfelPredictStableDepth(benchmark::State& state) {
  benchRender(state, [](const ff::StaticMap& m, const ff::SE3& T, const ff::CameraIntrinsics& c) {
    return m.predictStableDepth(T, c);
  });
}
BENCHMARK(BM_SurfelPredictStableDepth)->Arg(1)->Unit(benchmark::kMillisecond);

// What the pipeline does per frame: fuse the frame, then predict the model at its pose for the next
// frame's tracking. Argument: prediction level as above.
void BM_SurfelIntegratePredict(benchmark::State& state) {
  const Sequence& seq = sequence();
  ff::StaticMap map = warmMap(seq);
  const ff::CameraIntrinsics camera = seq.camera.atLevel(static_cast<int>(state.range(0)));
  size_t i = 0;
  for (auto _ : state) {
    const size_t k = i % seq.frames.size();
    map.integrate(seq.frames[k].frame, seq.camera, seq.frames[k].T_world_cam, seq.weights[k]);
    benchmark::DoNotOptimize(map.predict(seq.frames[k].T_world_cam, camera));
    ++i;
  }
  state.counters["surfels"] = static_cast<double>(map.size());
}
BENCHMARK(BM_SurfelIntegratePredict)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// The TSDF alternative: integration only (legacy Open3D has no ray caster for the prediction).
// Argument: voxel size in millimetres. Dynamic pixels are zeroed in the depth, as weights would.
void BM_Open3dTsdfIntegrate(benchmark::State& state) {
  const Sequence& seq = sequence();
  const double voxel_m = state.range(0) / 1000.0;
  open3d::pipelines::integration::ScalableTSDFVolume volume(voxel_m, 4 * voxel_m,
                                                            open3d::pipelines::integration::TSDFVolumeColorType::RGB8);
  const open3d::camera::PinholeCameraIntrinsic intrinsic(seq.camera.width, seq.camera.height, seq.camera.fx,
                                                         seq.camera.fy, seq.camera.cx, seq.camera.cy);
  std::vector<std::shared_ptr<open3d::geometry::RGBDImage>> images;
  for (size_t k = 0; k < seq.frames.size(); ++k) {
    const auto& f = seq.frames[k].frame;
    open3d::geometry::Image color, depth;
    color.Prepare(f.width(), f.height(), 3, 1);
    depth.Prepare(f.width(), f.height(), 1, 4);
    for (int y = 0; y < f.height(); ++y)
      for (int x = 0; x < f.width(); ++x) {
        const cv::Vec3b c = f.color.at<cv::Vec3b>(y, x);
        uint8_t* p = color.PointerAt<uint8_t>(x, y, 0);
        p[0] = c[2];
        p[1] = c[1];
        p[2] = c[0];
        *depth.PointerAt<float>(x, y) = seq.weights[k].at<float>(y, x) > 0.5f ? f.depth.at<float>(y, x) : 0.0f;
      }
    images.push_back(open3d::geometry::RGBDImage::CreateFromColorAndDepth(color, depth, 1.0, 4.0, false));
  }
  size_t i = 0;
  for (auto _ : state) {
    const size_t k = i % seq.frames.size();
    volume.Integrate(*images[k], intrinsic, seq.frames[k].T_world_cam.inverse().matrix());
    ++i;
  }
}
BENCHMARK(BM_Open3dTsdfIntegrate)->Arg(10)->Arg(20)->Unit(benchmark::kMillisecond);

}  // namespace
