#pragma once
// `flowfusion ros`: the system as a ROS 1 node (name `flowfusion`, remappable as any node), a thin
// adapter over the live seams: colour, depth and the colour CameraInfo, synchronised by an
// approximate-time policy, go into a queue of one (io/live_frame_queue.h), so the node stays live
// and counts what it drops; runSequence (pipeline/run.h) runs the system on them and a ResultSink
// publishes what it gives. README's "ROS node" lists the topics, parameters and services. This
// header needs no ROS headers: apps/cmd_ros.cpp includes it, and the ROS code is compiled apart
// (src/flowfusion/CMakeLists.txt says why as C++17).
#include <string>
#include <vector>

namespace ff::rosnode {

// The options `flowfusion ros` takes as `run` does; the node's parameters of the same names come
// after them (ros/node_params.h).
struct RosNodeOptions {
  std::string camera;                      // --camera; "" = from the CameraInfo
  bool undistort = true;                   // false: --no-undistort
  std::string config_file;                 // --config
  std::vector<std::string> overrides;      // --set, in order
  std::vector<std::string> ros_arguments;  // remappings (from:=to), _param:=value, __name:=...
};

// Checks the options (InputError naming the bad one, before anything connects), then runs the node
// until ROS shuts it down (SIGINT, SIGTERM, rosnode kill, the master); returns 0 after a clean
// shutdown, when it has written the run so far, marked partial, into ~save_dir if one is set.
int runRosNode(const RosNodeOptions& options);

}  // namespace ff::rosnode
