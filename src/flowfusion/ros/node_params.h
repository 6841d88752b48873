#pragma once
// The node's private parameters (~name) over the command line's options: the system's
// configuration in the order defaults, --config, ~config, --set, ~set (a string or a list of
// "section.key=value"), the camera (~camera as --camera), depth units, frame names, the map's
// publishing period and the save folder. A bad parameter is logged once with the reason and left
// at the value it would have without it: the node keeps running.
#include <optional>
#include <ros/node_handle.h>
#include <string>

#include "flowfusion/core/camera.h"
#include "flowfusion/pipeline/system_config.h"
#include "flowfusion/ros/ros_node.h"

namespace ff::rosnode {

struct NodeParams {
  SystemConfig config;
  std::optional<CameraModel> camera;  // ~camera or --camera; nullopt: the first usable CameraInfo
  bool undistort = true;              // ~undistort: undistort a lens with distortion, as `run` does
  double depth_scale = 1000;          // ~depth_scale: 16UC1 depth units per metre (ROS drivers: mm)
  std::string map_frame = "map";      // ~map_frame: the parent of the poses and the TF ("odom" for a robot with its own map)
  std::string camera_frame;           // ~camera_frame: the TF's child; "" = the colour image's frame_id
  bool publish_tf = true;             // ~publish_tf
  double map_period_s = 2;            // ~map_period_s: ~static_cloud at most this often; 0 = never
  std::string save_dir;               // ~save_dir: where ~save and a shutdown write; "" = no saving
  double sync_slop_s = 0.02;          // ~sync_slop_s: colour-depth stamps at most this far apart (as bags)
};

// `options` were checked by runRosNode; what the parameters say on top of them.
NodeParams readNodeParams(const ros::NodeHandle& private_nh, const RosNodeOptions& options);

// The configuration of the command line alone (liveDefaults(), --config, --set), checked: InputError naming
// the bad option.
SystemConfig commandLineConfig(const RosNodeOptions& options);

}  // namespace ff::rosnode
