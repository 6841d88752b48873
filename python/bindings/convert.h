#pragma once
// Conversions between NumPy arrays and the engine's types for the Python module, and the errors
// a user's bad input raises: ValueError naming the argument (wrong shape, dtype or size, a bad
// setting), FileNotFoundError naming a missing path. Every conversion is one OpenCV or memcpy
// pass over the data, never Python work per pixel.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <stdexcept>
#include <string>

#include "flowfusion/core/camera.h"
#include "flowfusion/core/se3.h"
#include "flowfusion/io/trajectory_io.h"

namespace ff::py_bind {

namespace py = pybind11;

// Raised as FileNotFoundError.
class MissingPath : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
// Raised as ValueError (an argument of the wrong shape, dtype or value).
class BadArgument : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// Throws MissingPath naming `what` when `path` does not exist.
void requireExists(const std::filesystem::path& path, const std::string& what);

// A checked array seen as a cv::Mat: a header over the C-contiguous data of `array` (the argument
// itself when it is C-contiguous, else a contiguous copy), valid while `array` lives. Reading it
// needs no GIL.
struct MatView {
  py::array array;
  cv::Mat mat;
};
// dtype exactly cv_depth's (else BadArgument naming `name`), 2-D, or 3-D with `channels` channels
// when channels > 1, not empty, at most kMaxImagePixels pixels and, when `expected` is not empty,
// of that size. Every check reads only the shape, so a huge, broadcast or strided array is refused
// before any copy.
MatView viewOfArray(const py::array& array, const std::string& name, int cv_depth, int channels,
                    cv::Size expected = {});
// The same checks, and a copy that owns its data.
cv::Mat matFromArray(const py::array& array, const std::string& name, int cv_depth, int channels,
                     cv::Size expected = {});

// A message of the engine for a Python user: the command-line flags it names replaced by the
// Python arguments that set the same thing ("--delta" -> "delta", "--set" -> "Config.set").
std::string pythonWording(const std::string& message);

// An HxW or HxWxC array owning a copy of `mat` (CV_8U, CV_16U, CV_32S or CV_32F).
py::array arrayFromMat(const cv::Mat& mat);

// 4x4 float64 from a pose, and back (BadArgument naming `name` unless a finite rigid transform).
py::array_t<double> arrayFromPose(const SE3& T);
SE3 poseFromArray(const py::handle& object, const std::string& name);

// Nx8 float64 (t tx ty tz qx qy qz qw, TUM) from a trajectory, and back (BadArgument naming `name`
// for a wrong shape, non-finite values, non-unit quaternions or unsorted timestamps).
py::array_t<double> arrayFromTrajectory(const Trajectory& trajectory);
Trajectory trajectoryFromArray(const py::handle& object, const std::string& name);
// An Nx8 array or a TUM trajectory file (MissingPath when it does not exist).
Trajectory trajectoryFromObject(const py::handle& object, const std::string& name);

// nlohmann JSON <-> Python objects (through the json module; configurations and results are small).
py::object pythonFromJson(const nlohmann::json& j);

}  // namespace ff::py_bind
