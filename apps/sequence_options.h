#pragma once
// Options shared by the subcommands that read a sequence and configure the system
// (`run`, `bench`): camera, depth scale, configuration file and per-setting overrides.
#include <CLI/CLI.hpp>
#include <memory>
#include <string>
#include <vector>

#include "config_sources.h"
#include "flowfusion/io/frame_source.h"
#include "flowfusion/io/tum_sequence.h"
#include "flowfusion/pipeline/flowfusion_system.h"

namespace ff::app {

struct SystemOptions {
  std::string camera;
  double depth_scale = 5000.0;
  CLI::Option* depth_scale_option = nullptr;  // tells whether --depth-scale was given
  std::string rgb_topic, depth_topic, groundtruth;  // bags
  ConfigSources config;
  std::string frames;
  bool no_segmentation = false;
  bool no_undistort = false;
  std::string tracking;

  void addTo(CLI::App* cmd) {
    cmd->add_option("--camera", camera,
                    "Intrinsics: fr1|fr2|fr3|fx,fy,cx,cy[,width,height[,k1,k2,p1,p2,k3]] (default: camera.txt or "
                    "folder name)");
    cmd->add_flag("--no-undistort", no_undistort, "Feed the raw images to the pinhole model (ignore lens distortion)");
    depth_scale_option = cmd->add_option("--depth-scale", depth_scale,
                                         "Raw depth units per metre (folders: 5000; bags' 16UC1: 1000)");
    cmd->add_option("--rgb-topic", rgb_topic, "Bag: colour image topic (default: found by name)");
    cmd->add_option("--depth-topic", depth_topic, "Bag: depth image topic (default: found by name)");
    cmd->add_option("--groundtruth", groundtruth, "Bag: ground-truth trajectory (TUM groundtruth.txt)");
    config.addTo(cmd, "SystemConfig");
    cmd->add_option("--frames", frames, "FIRST:LAST frame indices (inclusive)");
    cmd->add_flag("--no-segmentation", no_segmentation, "Plain robust odometry, no dynamic segmentation");
    cmd->add_option("--tracking", tracking,
                    "frame_to_keyframe (default; keyframes from the map, see pipeline.model_keyframes), "
                    "frame_to_frame or frame_to_model");
  }

  SequenceOptions sequenceOptions() const {
    SequenceOptions s;
    s.camera = camera;
    s.tum.depth_scale = depth_scale;
    if (depth_scale_option && depth_scale_option->count() > 0) s.bag.depth_scale = depth_scale;
    s.bag.rgb_topic = rgb_topic;
    s.bag.depth_topic = depth_topic;
    s.bag.groundtruth = groundtruth;
    s.undistort = !no_undistort;
    return s;
  }

  // The frame source for `path` over --frames.
  std::unique_ptr<FrameSource> openSource(const std::string& path) const {
    return openFrameSource(path, sequenceOptions(), frames.empty() ? FrameRange{} : parseFrameRange(frames));
  }

  // `defaults` below the --config file and the --set options (liveDefaults() for a live run).
  SystemConfig systemConfig(const SystemConfig& defaults = SystemConfig{}) const {
    std::vector<std::string> flags;
    if (no_segmentation) flags.push_back("pipeline.segmentation=false");
    if (!tracking.empty()) flags.push_back("pipeline.tracking=\"" + tracking + "\"");
    SystemConfig c = config.resolve(defaults, flags);
    validate(c);
    return c;
  }
};

}  // namespace ff::app
