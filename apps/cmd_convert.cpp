// `flowfusion convert BAG OUT`: a ROS 1 or ROS 2 bag written as a TUM-layout folder (io/bag_convert.h).
// SIGINT/SIGTERM stop it after the current frame with a marked partial result, as `run`.
#include <iostream>
#include <memory>

#include "command.h"
#include "flowfusion/core/output_folder.h"
#include "flowfusion/io/bag_convert.h"
#include "stop_signals.h"

namespace {

struct Options {
  std::string bag, out;
  ff::SequenceOptions sequence;
  bool overwrite = false;
};

void convert(const Options& o) {
  ff::refuseOverlap(o.out, o.bag, "the input bag");
  if (!o.sequence.bag.groundtruth.empty()) ff::refuseOverlap(o.out, o.sequence.bag.groundtruth, "the --groundtruth file");
  ff::setOutputCommand("convert");
  const ff::app::StopSignals signals;
  const ff::BagConversion c =
      ff::convertBagToTum(o.bag, o.out, o.sequence, o.overwrite, signals.flag(), signals.reason());
  if (!c.complete) {
    std::cerr << "flowfusion: convert stopped after " << c.frames << " frames: " << c.stop_reason
              << "; partial result in " << o.out << " (summary.json says so)\n";
    throw ff::app::ExitStatus{signals.exitStatus()};
  }
  std::cout << "convert: wrote " << c.frames << " frames (" << c.color_topic << ", " << c.depth_topic << ") to "
            << o.out << '\n';
  if (c.saturated_pixels > 0)
    std::cerr << "convert: " << c.saturated_pixels << " depth pixels beyond 13.1 m were written as 65535\n";
}

const ff::app::RegisterCommand convert_command("55-convert", [](CLI::App& app) {
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "convert", "Write a ROS 1 or ROS 2 bag as a TUM-layout folder (rgb/, depth/ 16-bit PNG at 5000 per metre, rgb.txt, "
                 "depth.txt, camera.txt, summary.json)");
  cmd->add_option("BAG", o->bag, "ROS 1 bag (.bag) or ROS 2 bag (rosbag2 folder, .mcap, .db3) with colour and depth image topics")->required();
  cmd->add_option("OUT", o->out, "Output folder")->required();
  cmd->add_option("--rgb-topic", o->sequence.bag.rgb_topic, "Colour topic (default: found by name)");
  cmd->add_option("--depth-topic", o->sequence.bag.depth_topic, "Depth topic (default: found by name)");
  cmd->add_option("--depth-scale", o->sequence.bag.depth_scale,
                  "Raw 16UC1 depth units per metre in the bag, 100 to 65535")
      ->capture_default_str();
  cmd->add_option("--camera", o->sequence.camera,
                  "Intrinsics: fr1|fr2|fr3|fx,fy,cx,cy[,width,height[,k1,k2,p1,p2,k3]] (default: CameraInfo)");
  cmd->add_option("--groundtruth", o->sequence.bag.groundtruth, "TUM groundtruth.txt to copy into the folder");
  cmd->add_flag("--overwrite", o->overwrite, "Write into a non-empty output folder");
  cmd->callback([o] { convert(*o); });
});

}  // namespace
