// `flowfusion convert BAG OUT`: a ROS 1 bag written as a TUM-layout folder (io/bag_convert.h).
#include <iostream>
#include <memory>

#include "command.h"
#include "flowfusion/core/output_folder.h"
#include "flowfusion/io/bag_convert.h"

namespace {

const ff::app::RegisterCommand convert_command("55-convert", [](CLI::App& app) {
  struct Options {
    std::string bag, out;
    ff::SequenceOptions sequence;
    bool overwrite = false;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "convert", "Write a ROS 1 bag as a TUM-layout folder (rgb/, depth/ 16-bit PNG at 5000 per metre, rgb.txt, "
                 "depth.txt, camera.txt)");
  cmd->add_option("BAG", o->bag, "ROS 1 bag (.bag) with colour and depth image topics")->required();
  cmd->add_option("OUT", o->out, "Output folder")->required();
  cmd->add_option("--rgb-topic", o->sequence.rgb_topic, "Colour topic (default: found by name)");
  cmd->add_option("--depth-topic", o->sequence.depth_topic, "Depth topic (default: found by name)");
  cmd->add_option("--depth-scale", o->sequence.bag_depth_scale, "Raw 16UC1 depth units per metre in the bag")
      ->capture_default_str();
  cmd->add_option("--camera", o->sequence.camera,
                  "Intrinsics: fr1|fr2|fr3|fx,fy,cx,cy[,width,height[,k1,k2,p1,p2,k3]] (default: CameraInfo)");
  cmd->add_option("--groundtruth", o->sequence.groundtruth, "TUM groundtruth.txt to copy into the folder");
  cmd->add_flag("--overwrite", o->overwrite, "Write into a non-empty output folder");
  cmd->callback([o] {
    ff::refuseOverlap(o->out, o->bag, "the input bag");
    ff::setOutputCommand("convert");
    const ff::BagConversion c = ff::convertBagToTum(o->bag, o->out, o->sequence, o->overwrite);
    std::cout << "convert: wrote " << c.frames << " frames (" << c.color_topic << ", " << c.depth_topic << ") to "
              << o->out << '\n';
    if (c.saturated_pixels > 0)
      std::cerr << "convert: " << c.saturated_pixels << " depth pixels beyond 13.1 m were written as 65535\n";
  });
});

}  // namespace
