// ff.Camera (intrinsics and lens distortion) and ff.Config (the system's settings, with the
// checks of --config and --set).
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cmath>
#include <cstdio>

#include "bindings.h"
#include "convert.h"
#include "flowfusion/core/config.h"
#include "flowfusion/core/error.h"
#include "flowfusion/pipeline/system_config.h"

namespace ff::py_bind {

namespace {

std::string cameraSpec(const CameraModel& c) {
  const CameraIntrinsics& k = c.intrinsics;
  std::vector<double> v = {k.fx, k.fy, k.cx, k.cy, double(k.width), double(k.height)};
  if (!c.distortion.none())
    v.insert(v.end(), {c.distortion.k1, c.distortion.k2, c.distortion.p1, c.distortion.p2, c.distortion.k3});
  std::string s;
  for (double x : v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.17g", x);
    if (!s.empty()) s += ',';
    s += buf;
  }
  return s;
}

CameraModel makeCamera(double fx, double fy, double cx, double cy, double width, double height,
                       const py::object& distortion) {
  std::vector<double> values = {fx, fy, cx, cy, width, height};
  if (!distortion.is_none()) {
    const auto d = distortion.cast<std::vector<double>>();
    if (d.size() != 5) throw BadArgument("distortion: expected 5 coefficients (k1, k2, p1, p2, k3), got " +
                                         std::to_string(d.size()));
    values.insert(values.end(), d.begin(), d.end());
  }
  if (const auto problem = cameraValuesProblem(values)) throw BadArgument("Camera: " + *problem);
  return cameraModelFromValues(values);
}

// The JSON text of a Python value (numbers, bools, strings, lists), NumPy scalars included.
std::string jsonText(py::object value) {
  if (py::hasattr(value, "item") && !py::isinstance<py::str>(value)) value = value.attr("item")();
  return py::module_::import("json").attr("dumps")(value).cast<std::string>();
}

SystemConfig withSetting(const SystemConfig& config, const std::string& key, const py::object& value) {
  nlohmann::json j = config;
  applyOverride(j, key + "=" + jsonText(value));
  SystemConfig result;
  try {
    result = j.get<SystemConfig>();
  } catch (const nlohmann::json::exception& e) {
    throw InputError("setting '" + key + "': " + e.what());
  }
  checkConverted(j, nlohmann::json(result));
  validate(result);
  return result;
}

py::object getSetting(const SystemConfig& config, const std::string& key) {
  const nlohmann::json j = config;
  const nlohmann::json* node = &j;
  size_t start = 0;
  while (true) {
    const size_t dot = key.find('.', start);
    const std::string part = key.substr(start, dot == std::string::npos ? std::string::npos : dot - start);
    if (!node->is_object() || !node->contains(part)) throw InputError("unknown setting '" + key + "'");
    node = &(*node)[part];
    if (dot == std::string::npos) break;
    start = dot + 1;
  }
  return pythonFromJson(*node);
}

}  // namespace

SequenceOptions sequenceOptions(const py::object& camera, double depth_scale, bool undistort) {
  SequenceOptions o;
  checkDepthScale(depth_scale, "depth_scale");
  o.tum.depth_scale = depth_scale;
  o.undistort = undistort;
  if (py::isinstance<CameraModel>(camera)) o.camera = cameraSpec(camera.cast<CameraModel>());
  else if (py::isinstance<py::str>(camera)) o.camera = camera.cast<std::string>();
  else if (!camera.is_none())
    throw py::type_error("camera: expected None, an ff.Camera or a spec string such as 'fr1', got " +
                         py::str(py::type::of(camera).attr("__name__")).cast<std::string>());
  return o;
}

FrameRange frameRange(const py::object& frames) {
  if (frames.is_none()) return FrameRange{};
  if (!py::isinstance<py::str>(frames))
    throw py::type_error("frames: expected None or a 'FIRST:LAST' string of frame indices, got " +
                         py::str(py::type::of(frames).attr("__name__")).cast<std::string>());
  return parseFrameRange(frames.cast<std::string>());
}

void bindCameraAndConfig(py::module_& m) {
  py::class_<CameraModel>(m, "Camera",
                          "Pinhole intrinsics (pixels) and optional Brown-Conrady lens distortion. The system works "
                          "with the pinhole model: frames must be undistorted (ff.TumSequence undistorts them).")
      .def(py::init(&makeCamera), py::arg("fx"), py::arg("fy"), py::arg("cx"), py::arg("cy"), py::arg("width"),
           py::arg("height"), py::arg("distortion") = py::none(),
           "Camera(fx, fy, cx, cy, width, height, distortion=None): focal lengths and principal point in pixels, "
           "image size in pixels, distortion (k1, k2, p1, p2, k3) in OpenCV's convention. ValueError on "
           "implausible values.")
      .def_static(
          "preset", [](const std::string& name) { return parseCameraModel(name, "Camera.preset"); }, py::arg("name"),
          "The TUM RGB-D benchmark's cameras 'fr1', 'fr2', 'fr3' (640x480, with their distortion), or a spec "
          "'fx,fy,cx,cy[,width,height[,k1,k2,p1,p2,k3]]' as --camera takes it.")
      .def_property_readonly("fx", [](const CameraModel& c) { return c.intrinsics.fx; }, "Focal length x, pixels.")
      .def_property_readonly("fy", [](const CameraModel& c) { return c.intrinsics.fy; }, "Focal length y, pixels.")
      .def_property_readonly("cx", [](const CameraModel& c) { return c.intrinsics.cx; }, "Principal point x, pixels.")
      .def_property_readonly("cy", [](const CameraModel& c) { return c.intrinsics.cy; }, "Principal point y, pixels.")
      .def_property_readonly("width", [](const CameraModel& c) { return c.intrinsics.width; }, "Image width, pixels.")
      .def_property_readonly("height", [](const CameraModel& c) { return c.intrinsics.height; },
                             "Image height, pixels.")
      .def_property_readonly(
          "distortion",
          [](const CameraModel& c) -> py::object {
            if (c.distortion.none()) return py::none();
            const LensDistortion& d = c.distortion;
            return py::make_tuple(d.k1, d.k2, d.p1, d.p2, d.k3);
          },
          "(k1, k2, p1, p2, k3) or None for a pinhole lens.")
      .def_property_readonly(
          "K",
          [](const CameraModel& c) {
            py::array_t<double> k({3, 3});
            const Eigen::Matrix3d K = c.intrinsics.K();
            for (int i = 0; i < 3; ++i)
              for (int j = 0; j < 3; ++j) k.mutable_at(i, j) = K(i, j);
            return k;
          },
          "3x3 intrinsic matrix (float64).")
      .def("__repr__", [](const CameraModel& c) { return "flowfusion.Camera('" + cameraSpec(c) + "')"; });

  py::class_<SystemConfig>(m, "Config",
                           "The system's settings, one section per stage (the config.json `flowfusion run` "
                           "writes). Keys and checks are those of --config and --set.")
      .def(py::init<>(), "The defaults.")
      .def_static(
          "load",
          [](const std::filesystem::path& path) {
            requireExists(path, "configuration file");
            SystemConfig c = resolveConfig(SystemConfig{}, path.string(), {});
            validate(c);
            return c;
          },
          py::arg("path"),
          "Defaults overridden by a JSON file (a run's config.json is one). FileNotFoundError when it is missing, "
          "ValueError naming the setting for an unknown key or a bad value.")
      .def(
          "set",
          [](SystemConfig& c, const std::string& key, const py::object& value) { c = withSetting(c, key, value); },
          py::arg("key"), py::arg("value"),
          "Sets 'section.key' to value, as --set section.key=value: unknown keys, wrong types and out-of-range "
          "values raise ValueError naming the setting and leave the configuration unchanged.")
      .def("get", &getSetting, py::arg("key"), "The value of 'section.key' (or a whole section as a dict).")
      .def(
          "to_dict", [](const SystemConfig& c) { return pythonFromJson(nlohmann::json(c)); },
          "Every setting as nested dicts (JSON types).")
      .def(
          "save", [](const SystemConfig& c, const std::filesystem::path& path) { writeJsonFile(path.string(), c); },
          py::arg("path"), "Writes the settings as JSON (a valid --config file).")
      .def("__repr__", [](const SystemConfig& c) { return "flowfusion.Config(" + nlohmann::json(c).dump() + ")"; });
}

}  // namespace ff::py_bind
