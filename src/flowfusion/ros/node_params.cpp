#include "flowfusion/ros/node_params.h"

#include <ros/console.h>

#include <cmath>
#include <functional>

#include "flowfusion/core/config.h"
#include "flowfusion/core/error.h"
#include "flowfusion/io/tum_sequence.h"

namespace ff::rosnode {

namespace {

// A configuration as JSON with one more layer applied, kept only when it converts and validates.
bool tryLayer(nlohmann::json& config, const std::string& what, const std::function<void(nlohmann::json&)>& apply) {
  nlohmann::json next = config;
  try {
    apply(next);
    const SystemConfig converted = next.get<SystemConfig>();
    checkConverted(next, nlohmann::json(converted));
    validate(converted);
  } catch (const std::exception& e) {
    ROS_ERROR_STREAM("flowfusion: parameter " << what << " ignored: " << e.what());
    return false;
  }
  config = std::move(next);
  return true;
}

// ~set as a list of strings: a string, or a list of strings.
std::vector<std::string> stringList(const ros::NodeHandle& nh, const std::string& key) {
  XmlRpc::XmlRpcValue value;
  if (!nh.getParam(key, value)) return {};
  if (value.getType() == XmlRpc::XmlRpcValue::TypeString) return {static_cast<std::string>(value)};
  std::vector<std::string> out;
  if (value.getType() == XmlRpc::XmlRpcValue::TypeArray) {
    for (int i = 0; i < value.size(); ++i) {
      if (value[i].getType() == XmlRpc::XmlRpcValue::TypeString) out.push_back(static_cast<std::string>(value[i]));
      else ROS_ERROR_STREAM("flowfusion: parameter ~" << key << "[" << i << "] ignored: not a string section.key=value");
    }
    return out;
  }
  ROS_ERROR_STREAM("flowfusion: parameter ~" << key << " ignored: not a string or a list of section.key=value strings");
  return {};
}

SystemConfig resolveLayers(const ros::NodeHandle& nh, const RosNodeOptions& options) {
  nlohmann::json config = nlohmann::json(liveDefaults());
  if (!options.config_file.empty()) mergeConfig(config, readJsonFile(options.config_file), options.config_file);
  if (std::string file; nh.getParam("config", file))
    tryLayer(config, "~config=" + file, [&](nlohmann::json& j) { mergeConfig(j, readJsonFile(file), file); });
  else if (nh.hasParam("config"))
    ROS_ERROR("flowfusion: parameter ~config ignored: not a string (a JSON file, as --config)");
  for (const std::string& o : options.overrides) applyOverride(config, o);
  for (const std::string& o : stringList(nh, "set"))
    tryLayer(config, "~set " + o, [&](nlohmann::json& j) { applyOverride(j, o); });
  return config.get<SystemConfig>();
}

// `key` read into `value` when it is set and `ok` accepts it; else logged, `value` unchanged.
template <class T>
void readParam(const ros::NodeHandle& nh, const std::string& key, T& value, const std::string& want,
               const std::function<bool(const T&)>& ok = {}) {
  if (!nh.hasParam(key)) return;
  T read{};
  if (nh.getParam(key, read) && (!ok || ok(read))) {
    value = read;
    return;
  }
  ROS_ERROR_STREAM("flowfusion: parameter ~" << key << " ignored: must be " << want);
}

}  // namespace

SystemConfig commandLineConfig(const RosNodeOptions& options) {
  SystemConfig c = resolveConfig(liveDefaults(), options.config_file, options.overrides);
  validate(c);
  return c;
}

NodeParams readNodeParams(const ros::NodeHandle& nh, const RosNodeOptions& options) {
  NodeParams p;
  p.config = resolveLayers(nh, options);
  if (!options.camera.empty()) p.camera = parseCameraModel(options.camera);
  if (std::string spec; nh.getParam("camera", spec) && !spec.empty()) {
    try {
      p.camera = parseCameraModel(spec, "~camera");
    } catch (const InputError& e) {
      ROS_ERROR_STREAM("flowfusion: parameter ~camera ignored: " << e.what());
    }
  }
  p.undistort = options.undistort;
  readParam<bool>(nh, "undistort", p.undistort, "true or false");
  readParam<double>(nh, "depth_scale", p.depth_scale, "16UC1 depth units per metre, 100 to 65535", [](const double& s) {
    try {
      checkDepthScale(s, "~depth_scale");
      return true;
    } catch (const InputError&) {
      return false;
    }
  });
  const auto frame_name = [](const std::string& s) { return !s.empty() && s.find(' ') == std::string::npos; };
  readParam<std::string>(nh, "map_frame", p.map_frame, "a frame name without spaces", frame_name);
  readParam<std::string>(nh, "camera_frame", p.camera_frame, "a frame name without spaces", frame_name);
  readParam<bool>(nh, "publish_tf", p.publish_tf, "true or false");
  readParam<double>(nh, "map_period_s", p.map_period_s, "a period in seconds, 0 or more (0: never)",
                    [](const double& s) { return std::isfinite(s) && s >= 0; });
  readParam<std::string>(nh, "save_dir", p.save_dir, "a folder name");
  readParam<double>(nh, "sync_slop_s", p.sync_slop_s, "seconds, more than 0 and at most 1",
                    [](const double& s) { return std::isfinite(s) && s > 0 && s <= 1; });
  return p;
}

}  // namespace ff::rosnode
