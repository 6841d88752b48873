// `flowfusion convert-results RUN OUT.mcap`: an existing run folder (trajectory.txt, masks/,
// map_points.ply, summary.json naming its sequence) written as the MCAP file `run --mcap` writes
// (pipeline/mcap_sink.h), the colour and depth read again from the run's sequence. The images
// are the sequence's raw pixels, as masks/ holds them.
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "command.h"
#include "flowfusion/core/config.h"
#include "flowfusion/core/error.h"
#include "flowfusion/io/frame_source.h"
#include "flowfusion/io/trajectory_io.h"
#include "flowfusion/io/tum_sequence.h"
#include "flowfusion/sinks/mcap_sink.h"

namespace fs = std::filesystem;

namespace {

struct Options {
  std::string run, out, sequence;
  ff::SequenceOptions source;
  double depth_scale = 0;  // raw depth units per metre when given (0: the source's default)
};

// The points of a map_points.ply as the run wrote it (binary little endian: double x y z, any
// further double properties, uchar red green blue); InputError naming the file otherwise.
std::vector<ff::McapMapPoint> readMapPoints(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return {};
  std::string line;
  size_t count = 0, doubles = 0, bytes = 0;
  bool little = false;
  while (std::getline(in, line) && line != "end_header") {
    std::istringstream words(line);
    std::string key, type, name;
    words >> key;
    if (key == "format") little = line.find("binary_little_endian") != std::string::npos;
    if (key == "element" && (words >> type >> count) && type != "vertex") throw ff::InputError(path + ": unexpected element " + type);
    if (key == "property" && (words >> type >> name)) (type == "double" ? doubles : bytes) += 1;
  }
  if (!little || doubles < 3 || bytes != 3 || line != "end_header")
    throw ff::InputError(path + ": not the binary map_points.ply a run writes (double x y z ..., uchar red green blue)");
  const size_t stride = doubles * 8 + 3;
  std::vector<char> data(count * stride);
  if (!in.read(data.data(), std::streamsize(data.size()))) throw ff::InputError(path + ": ends before its " + std::to_string(count) + " points");
  std::vector<ff::McapMapPoint> points(count);
  for (size_t i = 0; i < count; ++i) {
    double xyz[3];
    std::memcpy(xyz, &data[i * stride], sizeof xyz);
    points[i].position = Eigen::Vector3d(xyz[0], xyz[1], xyz[2]).cast<float>();
    std::memcpy(points[i].rgb, &data[i * stride + doubles * 8], 3);
  }
  return points;
}

void convertResults(const Options& o) {
  const fs::path run(o.run);
  const nlohmann::json summary = ff::readJsonFile((run / "summary.json").string());
  const std::string sequence =
      !o.sequence.empty() ? o.sequence : summary.is_object() ? summary.value("sequence", std::string()) : "";
  if (sequence.empty()) throw ff::InputError((run / "summary.json").string() + ": names no sequence; give --sequence");
  const ff::Trajectory trajectory = ff::readTrajectory((run / "trajectory.txt").string());
  ff::SequenceOptions options = o.source;
  options.undistort = false;  // masks/ holds the raw pixels
  if (o.depth_scale > 0) options.tum.depth_scale = options.bag.depth_scale = o.depth_scale;
  const std::unique_ptr<ff::FrameSource> source = ff::openFrameSource(sequence, options);
  ff::McapSink sink(o.out);
  ff::RunInfo info;
  info.source = source->name();
  info.camera = source->camera();
  sink.begin(info);
  size_t next = 0, written = 0;
  while (next < trajectory.size()) {
    const std::optional<ff::RgbdFrame> frame = source->next();
    if (!frame) break;
    if (std::abs(frame->timestamp - trajectory[next].timestamp) > 5e-7) continue;  // trajectory.txt: 6 decimals
    ff::FrameResult result;
    result.timestamp = frame->timestamp;
    result.T_world_cam = trajectory[next++].T_world_cam;
    const fs::path mask = run / "masks" / (ff::timestampName(frame->timestamp) + ".png");
    result.dynamic_mask = cv::imread(mask.string(), cv::IMREAD_UNCHANGED);
    sink.frame(*frame, result);
    ++written;
  }
  if (next < trajectory.size())
    throw ff::InputError(sequence + ": has no frame at " + ff::timestampName(trajectory[next].timestamp) + " of " +
                         (run / "trajectory.txt").string() + " (is it the run's sequence? give --sequence)");
  sink.finish(trajectory, readMapPoints((run / "map_points.ply").string()));
  std::cout << "convert-results: wrote " << written << " frames of " << o.run << " to " << o.out << '\n';
}

const ff::app::RegisterCommand convert_results_command("56-convert-results", [](CLI::App& app) {
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "convert-results", "Write a run folder as an MCAP file for Foxglove, as `run --mcap` does (images from its sequence)");
  cmd->add_option("RUN", o->run, "Run folder (trajectory.txt, masks/, map_points.ply, summary.json)")->required();
  cmd->add_option("OUT", o->out, "MCAP file to write")->required();
  cmd->add_option("--sequence", o->sequence, "The run's sequence (default: summary.json's)");
  cmd->add_option("--camera", o->source.camera, "Intrinsics as given to the run");
  cmd->add_option("--depth-scale", o->depth_scale, "Raw depth units per metre, as given to the run");
  cmd->add_option("--rgb-topic", o->source.bag.rgb_topic, "Bags: colour topic, as given to the run");
  cmd->add_option("--depth-topic", o->source.bag.depth_topic, "Bags: depth topic, as given to the run");
  cmd->callback([o] { convertResults(*o); });
});

}  // namespace
