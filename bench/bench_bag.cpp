// Micro-benchmark of reading RGB-D frames: a ROS 1 bag (rgb8 colour, 16UC1 depth; uncompressed,
// lz4, bz2) against the TUM folder of the same 30 synthetic 640x480 frames, opened and decoded
// into RgbdFrames as `run` reads them (frames/s = items_per_second; the bag's open includes its
// pass over the stamps).
//   build-*/bench/flowfusion_microbench --benchmark_filter=Read
#include <benchmark/benchmark.h>

#ifdef FLOWFUSION_HAVE_ROSBAG

#include <rosbag/bag.h>
#include <unistd.h>

#include <filesystem>
#include <functional>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "flowfusion/io/bag_source.h"
#include "flowfusion/io/ros_messages.h"
#include "flowfusion/io/tum_folder_source.h"
#include "flowfusion/synth/synthetic_scene.h"

namespace fs = std::filesystem;

namespace {

constexpr int kFrames = 30;

void writeImage(rosbag::Bag& bag, const std::string& topic, double t, const cv::Mat& m, const std::string& encoding) {
  ff::ros1::ImageMsg msg;
  msg.header.stamp = ros::Time(t);
  msg.height = m.rows;
  msg.width = m.cols;
  msg.encoding = encoding;
  msg.step = static_cast<uint32_t>(m.cols * m.elemSize());
  msg.data.assign(m.data, m.data + m.total() * m.elemSize());
  bag.write(topic, msg.header.stamp, msg);
}

// The folder (as `synth` writes it) and its frames as bags, removed at exit.
struct Recording {
  fs::path root = fs::temp_directory_path() / ("flowfusion_bench_bag_" + std::to_string(::getpid()));
  std::string folder = (root / "seq").string();
  Recording() {
    ff::synth::SynthConfig c;
    c.frames = kFrames;
    const ff::synth::SyntheticScene scene(c);
    ff::synth::writeSequence(scene, folder);
    const ff::TumSequence seq = ff::TumSequence::open(folder);
    for (const auto& [name, compression] :
         {std::pair{"none", rosbag::compression::Uncompressed}, std::pair{"lz4", rosbag::compression::LZ4},
          std::pair{"bz2", rosbag::compression::BZ2}}) {
      rosbag::Bag out(bag(name), rosbag::bagmode::Write);
      out.setCompression(compression);
      ff::ros1::CameraInfoMsg info;
      info.width = seq.camera().width;
      info.height = seq.camera().height;
      info.K = {seq.camera().fx, 0, seq.camera().cx, 0, seq.camera().fy, seq.camera().cy, 0, 0, 1};
      out.write("/camera/rgb/camera_info", ros::Time(seq.entry(0).rgb_timestamp), info);
      for (size_t i = 0; i < seq.size(); ++i) {
        cv::Mat rgb;
        cv::cvtColor(cv::imread(seq.entry(i).rgb_path, cv::IMREAD_UNCHANGED), rgb, cv::COLOR_BGR2RGB);
        writeImage(out, "/camera/rgb/image_color", seq.entry(i).rgb_timestamp, rgb, "rgb8");
        writeImage(out, "/camera/depth/image", seq.entry(i).depth_timestamp,
                   cv::imread(seq.entry(i).depth_path, cv::IMREAD_UNCHANGED), "16UC1");
      }
    }
  }
  ~Recording() { fs::remove_all(root); }
  std::string bag(const std::string& compression) const { return (root / (compression + ".bag")).string(); }
};

const Recording& recording() {
  static const Recording r;
  return r;
}

void readAll(benchmark::State& state, const std::function<std::unique_ptr<ff::FrameSource>()>& open) {
  int64_t frames = 0;
  for (auto _ : state) {
    const auto source = open();
    while (auto f = source->next()) {
      benchmark::DoNotOptimize(f->depth.data);
      ++frames;
    }
  }
  state.SetItemsProcessed(frames);
}

void BM_ReadFolder(benchmark::State& state) {
  const std::string folder = recording().folder;
  readAll(state, [&] { return std::make_unique<ff::TumFolderSource>(ff::TumSequence::open(folder)); });
}
BENCHMARK(BM_ReadFolder)->Unit(benchmark::kMillisecond);

void BM_ReadBag(benchmark::State& state, const char* compression) {
  const std::string path = recording().bag(compression);
  ff::SequenceOptions options;
  options.bag.depth_scale = 5000;
  readAll(state, [&] { return std::make_unique<ff::BagSource>(path, options); });
}
BENCHMARK_CAPTURE(BM_ReadBag, none, "none")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ReadBag, lz4, "lz4")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ReadBag, bz2, "bz2")->Unit(benchmark::kMillisecond);

}  // namespace

#endif  // FLOWFUSION_HAVE_ROSBAG
