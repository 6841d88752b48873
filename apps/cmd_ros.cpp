// `flowfusion ros [--camera ...] [--config FILE] [--set k=v]... [ROS arguments]`: the system as a
// ROS 1 node (ros/ros_node.h), with `run`'s configuration options; ROS arguments are remappings
// (from:=to), private parameters (_name:=value) and __name:=..., as any node takes them. A build
// without Debian's ROS 1 packages says how to enable the node.
#include <stdexcept>

#include "command.h"
#include "config_sources.h"
#include "flowfusion/core/error.h"

#ifdef FLOWFUSION_HAVE_ROS_NODE
#include "flowfusion/ros/ros_node.h"
#endif

namespace ff::app {
namespace {

struct RosCommand {
  std::string camera;
  bool no_undistort = false;
  ConfigSources config;
  std::vector<std::string> ros_arguments;
};

void execute(RosCommand c) {
  // `--set a=1 _p:=v` gives --set both: a ROS argument is never a setting.
  std::vector<std::string>& sets = c.config.overrides;
  for (auto it = sets.begin(); it != sets.end();)
    if (it->find(":=") != std::string::npos) {
      c.ros_arguments.push_back(*it);
      it = sets.erase(it);
    } else {
      ++it;
    }
  for (const std::string& a : c.ros_arguments)
    if (a.find(":=") == std::string::npos)
      throw InputError("unexpected argument '" + a + "': ROS arguments are from:=to, _param:=value or __name:=node");
#ifdef FLOWFUSION_HAVE_ROS_NODE
  rosnode::RosNodeOptions o;
  o.camera = c.camera;
  o.undistort = !c.no_undistort;
  o.config_file = c.config.file;
  o.overrides = c.config.overrides;
  o.ros_arguments = c.ros_arguments;
  if (const int status = rosnode::runRosNode(o); status != 0) throw ExitStatus{status};
#else
  throw InputError(
      "this flowfusion was built without the ROS 1 node; install Debian's ROS 1 packages (the ROS 1 node block of "
      "scripts/install-deps.sh: ros-core libroscpp-dev libmessage-filters-dev libtf2-ros-dev libnav-msgs-dev "
      "libdiagnostic-updater-dev libstd-srvs-dev, with the bag packages), configure and build again");
#endif
}

const RegisterCommand reg("5-ros", [](CLI::App& app) {
  auto c = std::make_shared<RosCommand>();
  CLI::App* cmd = app.add_subcommand(
      "ros", "Run as a ROS 1 node: colour, depth and CameraInfo in; odometry, TF, path, mask, static cloud out");
  cmd->add_option("--camera", c->camera,
                  "Intrinsics: fr1|fr2|fr3|fx,fy,cx,cy[,width,height[,k1,k2,p1,p2,k3]] (default: the CameraInfo)");
  cmd->add_flag("--no-undistort", c->no_undistort, "Feed the raw images to the pinhole model (ignore lens distortion)");
  c->config.addTo(cmd, "SystemConfig");
  cmd->add_option("ros_arguments", c->ros_arguments,
                  "ROS arguments: remappings /camera/rgb/image_color:=/camera/color/image_raw, _param:=value, "
                  "__name:=node");
  cmd->callback([c]() { execute(*c); });
});

}  // namespace
}  // namespace ff::app
