#include "convert.h"

#include <cctype>
#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>
#include <pybind11/stl/filesystem.h>

#include "flowfusion/core/image_file.h"

namespace ff::py_bind {

namespace {

std::string shapeText(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

std::string dtypeText(const py::array& a) { return py::str(a.dtype()).cast<std::string>(); }

bool dtypeMatches(const py::array& a, int cv_depth) {
  switch (cv_depth) {
    case CV_8U: return py::isinstance<py::array_t<uint8_t>>(a);
    case CV_16U: return py::isinstance<py::array_t<uint16_t>>(a);
    case CV_32F: return py::isinstance<py::array_t<float>>(a);
    case CV_64F: return py::isinstance<py::array_t<double>>(a);
    default: return false;
  }
}

const char* dtypeName(int cv_depth) {
  switch (cv_depth) {
    case CV_8U: return "uint8";
    case CV_16U: return "uint16";
    case CV_32F: return "float32";
    default: return "float64";
  }
}

// A float64 array of the given shape (rows x cols) converted from any real dtype.
using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

DoubleArray doubleMatrix(const py::handle& object, const std::string& name,
                                                     py::ssize_t rows, py::ssize_t cols) {
  if (!py::isinstance<py::array>(object) && !py::isinstance<py::sequence>(object))
    throw BadArgument(name + ": expected a NumPy array, got " + py::str(py::type::of(object)).cast<std::string>());
  const py::array a = py::array::ensure(object);
  if (!a) throw BadArgument(name + ": not convertible to a NumPy array");
  const char kind = a.dtype().kind();
  if (kind != 'f' && kind != 'i' && kind != 'u')
    throw BadArgument(name + ": expected a real-valued array, got dtype " + dtypeText(a));
  if (a.ndim() != 2 || (rows >= 0 && a.shape(0) != rows) || a.shape(1) != cols)
    throw BadArgument(name + ": expected shape (" + (rows >= 0 ? std::to_string(rows) : std::string("N")) + ", " +
                      std::to_string(cols) + "), got " + shapeText(a));
  return DoubleArray::ensure(a);
}

}  // namespace

void requireExists(const std::filesystem::path& path, const std::string& what) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw MissingPath(what + " '" + path.string() + "' does not exist");
}

MatView viewOfArray(const py::array& array, const std::string& name, int cv_depth, int channels, cv::Size expected) {
  if (!dtypeMatches(array, cv_depth))
    throw BadArgument(name + ": expected dtype " + dtypeName(cv_depth) + ", got " + dtypeText(array));
  const bool shape_ok = channels == 1 ? array.ndim() == 2
                                      : array.ndim() == 3 && array.shape(2) == static_cast<py::ssize_t>(channels);
  if (!shape_ok)
    throw BadArgument(name + ": expected shape (H, W" + (channels == 1 ? std::string() : ", " + std::to_string(channels)) +
                      "), got " + shapeText(array));
  const py::ssize_t rows = array.shape(0), cols = array.shape(1);
  if (rows == 0 || cols == 0) throw BadArgument(name + ": the image is empty " + shapeText(array));
  if (rows > kMaxImagePixels / cols)
    throw BadArgument(name + ": shape " + shapeText(array) + " holds more than " + std::to_string(kMaxImagePixels) +
                      " pixels");
  if (!expected.empty() && (cols != expected.width || rows != expected.height))
    throw BadArgument(name + ": the image is " + std::to_string(cols) + "x" + std::to_string(rows) +
                      " (WxH), the camera is " + std::to_string(expected.width) + "x" +
                      std::to_string(expected.height));
  MatView view{py::array::ensure(array, py::array::c_style), {}};
  if (!view.array) throw py::error_already_set();
  view.mat = cv::Mat(static_cast<int>(rows), static_cast<int>(cols), CV_MAKETYPE(cv_depth, channels),
                     const_cast<void*>(view.array.data()));
  return view;
}

cv::Mat matFromArray(const py::array& array, const std::string& name, int cv_depth, int channels, cv::Size expected) {
  return viewOfArray(array, name, cv_depth, channels, expected).mat.clone();
}

std::string pythonWording(const std::string& message) {
  static const std::pair<const char*, const char*> kNames[] = {
      {"--delta", "delta"},          {"--max-diff", "max_diff"},       {"--frames", "frames"},
      {"--depth-scale", "depth_scale"}, {"--set", "Config.set"},       {"--config", "Config.load"},
      {"--overwrite", "overwrite=True"}, {"--no-undistort", "undistort=False"}, {"--camera", "camera"},
      {"--offset", "offset"}};
  std::string out = message;
  for (const auto& [flag, name] : kNames) {
    const size_t n = std::strlen(flag);
    for (size_t at = out.find(flag); at != std::string::npos; at = out.find(flag, at)) {
      const bool whole = at + n == out.size() || !(std::isalnum(static_cast<unsigned char>(out[at + n])) ||
                                                   out[at + n] == '-' || out[at + n] == '_');
      if (!whole) {
        at += n;
        continue;
      }
      out.replace(at, n, name);
      at += std::strlen(name);
    }
  }
  return out;
}

py::array arrayFromMat(const cv::Mat& mat) {
  const cv::Mat m = mat.isContinuous() ? mat : mat.clone();
  std::vector<py::ssize_t> shape = {m.rows, m.cols};
  if (m.channels() > 1) shape.push_back(m.channels());
  py::array out;
  switch (m.depth()) {
    case CV_8U: out = py::array_t<uint8_t>(shape); break;
    case CV_16U: out = py::array_t<uint16_t>(shape); break;
    case CV_32S: out = py::array_t<int32_t>(shape); break;
    case CV_32F: out = py::array_t<float>(shape); break;
    default: throw std::logic_error("arrayFromMat: unsupported image type");
  }
  std::memcpy(out.mutable_data(), m.data, m.total() * m.elemSize());
  return out;
}

py::array_t<double> arrayFromPose(const SE3& T) {
  py::array_t<double> out({4, 4});
  auto r = out.mutable_unchecked<2>();
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) r(i, j) = T.matrix()(i, j);
  return out;
}

SE3 poseFromArray(const py::handle& object, const std::string& name) {
  const auto a = doubleMatrix(object, name, 4, 4);
  const auto r = a.unchecked<2>();
  Eigen::Matrix4d m;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) m(i, j) = r(i, j);
  if (!m.allFinite()) throw BadArgument(name + ": the pose holds NaN or infinite values");
  const Eigen::Matrix3d R = m.topLeftCorner<3, 3>();
  if (!m.row(3).isApprox(Eigen::RowVector4d(0, 0, 0, 1), 1e-9) ||
      !(R.transpose() * R).isApprox(Eigen::Matrix3d::Identity(), 1e-6) || R.determinant() < 0)
    throw BadArgument(name + ": not a rigid transform (the rotation must be orthonormal with determinant +1 "
                             "and the last row 0 0 0 1)");
  SE3 T = SE3::Identity();
  T.matrix() = m;
  return T;
}

py::array_t<double> arrayFromTrajectory(const Trajectory& trajectory) {
  py::array_t<double> out({static_cast<py::ssize_t>(trajectory.size()), py::ssize_t{8}});
  auto r = out.mutable_unchecked<2>();
  for (size_t i = 0; i < trajectory.size(); ++i) {
    const auto& p = trajectory[i];
    const Eigen::Quaterniond q(p.T_world_cam.rotation());
    const Eigen::Vector3d t = p.T_world_cam.translation();
    const double row[8] = {p.timestamp, t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()};
    for (int j = 0; j < 8; ++j) r(static_cast<py::ssize_t>(i), j) = row[j];
  }
  return out;
}

Trajectory trajectoryFromArray(const py::handle& object, const std::string& name) {
  const auto a = doubleMatrix(object, name, -1, 8);
  const auto r = a.unchecked<2>();
  Trajectory traj;
  for (py::ssize_t i = 0; i < r.shape(0); ++i) {
    const std::string row = name + " row " + std::to_string(i);
    for (int j = 0; j < 8; ++j)
      if (!std::isfinite(r(i, j))) throw BadArgument(row + ": NaN or infinite value");
    const Eigen::Quaterniond q(r(i, 7), r(i, 4), r(i, 5), r(i, 6));
    if (std::abs(q.norm() - 1.0) > 1e-2)
      throw BadArgument(row + ": quaternion (qx qy qz qw, columns 4-7) is not of unit length");
    if (!traj.empty() && r(i, 0) <= traj.back().timestamp)
      throw BadArgument(row + ": timestamps (column 0) must increase strictly");
    traj.push_back({r(i, 0), poseFromTranslationQuaternion({r(i, 1), r(i, 2), r(i, 3)}, q)});
  }
  if (traj.empty()) throw BadArgument(name + ": the trajectory holds no poses");
  return traj;
}

Trajectory trajectoryFromObject(const py::handle& object, const std::string& name) {
  if (py::isinstance<py::str>(object) || py::hasattr(object, "__fspath__")) {
    const auto path = object.cast<std::filesystem::path>();
    requireExists(path, name + " trajectory file");
    return readTrajectory(path.string());
  }
  return trajectoryFromArray(object, name);
}

py::object pythonFromJson(const nlohmann::json& j) { return py::module_::import("json").attr("loads")(j.dump()); }

}  // namespace ff::py_bind
