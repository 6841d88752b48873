#include "flowfusion/core/camera.h"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "flowfusion/core/error.h"

namespace ff {

CameraIntrinsics CameraIntrinsics::atLevel(int level) const {
  CameraIntrinsics c = *this;
  for (int i = 0; i < level; ++i) {
    // A 2x2 average puts the new pixel centre between the old ones: u' = (u - 0.5) / 2.
    c.fx *= 0.5;
    c.fy *= 0.5;
    c.cx = (c.cx - 0.5) * 0.5;
    c.cy = (c.cy - 0.5) * 0.5;
    c.width /= 2;
    c.height /= 2;
  }
  return c;
}

Eigen::Matrix3d CameraIntrinsics::K() const {
  Eigen::Matrix3d k;
  k << fx, 0, cx, 0, fy, cy, 0, 0, 1;
  return k;
}

std::optional<CameraIntrinsics> freiburgPreset(int n) {
  // Values from the TUM RGB-D benchmark's "file formats" page (colour camera).
  switch (n) {
    case 1: return CameraIntrinsics{517.3, 516.5, 318.6, 255.3, 640, 480};
    case 2: return CameraIntrinsics{520.9, 521.0, 325.1, 249.7, 640, 480};
    case 3: return CameraIntrinsics{535.4, 539.2, 320.1, 247.6, 640, 480};
    default: return std::nullopt;
  }
}

std::optional<LensDistortion> freiburgDistortion(int n) {
  switch (n) {
    case 1: return LensDistortion{0.2624, -0.9531, -0.0054, 0.0026, 1.1633};
    case 2: return LensDistortion{0.2312, -0.7849, -0.0033, -0.0001, 0.9172};
    case 3: return LensDistortion{};
    default: return std::nullopt;
  }
}

CameraModel cameraModelFromValues(const std::vector<double>& v) {
  if (v.size() != 4 && v.size() != 6 && v.size() != 11)
    throw std::invalid_argument("cameraModelFromValues: 4, 6 or 11 values, got " + std::to_string(v.size()));
  CameraModel m;
  m.intrinsics = CameraIntrinsics{v[0], v[1], v[2], v[3], 640, 480};
  if (v.size() >= 6) {
    m.intrinsics.width = static_cast<int>(v[4]);
    m.intrinsics.height = static_cast<int>(v[5]);
  }
  if (v.size() == 11) m.distortion = LensDistortion{v[6], v[7], v[8], v[9], v[10]};
  return m;
}

std::optional<std::string> cameraValuesProblem(const std::vector<double>& v) {
  for (double x : v)
    if (!std::isfinite(x)) return "a value is not finite";
  const double width = v.size() >= 6 ? v[4] : 640, height = v.size() >= 6 ? v[5] : 480;
  for (double side : {width, height})
    if (!(side >= 1 && side <= 100000) || side != std::floor(side))
      return "the image size must be whole numbers of 1 to 100000 pixels";
  if (!(v[0] >= 1 && v[0] <= 1e6 && v[1] >= 1 && v[1] <= 1e6)) return "focal lengths must be 1 to 1e6 pixels";
  if (!(std::abs(v[2] - width / 2) <= 1.5 * width && std::abs(v[3] - height / 2) <= 1.5 * height))
    return "the principal point must lie within one image size of the image";
  for (size_t k = 6; k < v.size(); ++k)
    if (std::abs(v[k]) > 1000) return "distortion coefficients must lie within +-1000";
  return std::nullopt;
}

CameraIntrinsics parseCamera(const std::string& spec, const std::string& what) {
  return parseCameraModel(spec, what).intrinsics;
}

CameraModel parseCameraModel(const std::string& spec_in, const std::string& what) {
  std::string spec;
  for (char ch : spec_in)
    if (ch != ' ' && ch != '\t' && ch != '\n' && ch != '\r') spec += ch;
  const std::string expected = "' is not fr1, fr2, fr3 or fx,fy,cx,cy[,width,height[,k1,k2,p1,p2,k3]]";
  if (spec == "fr1" || spec == "fr2" || spec == "fr3")
    return {*freiburgPreset(spec[2] - '0'), *freiburgDistortion(spec[2] - '0')};
  std::vector<double> v;
  std::stringstream ss(spec);
  std::string item;
  while (std::getline(ss, item, ',')) {
    try {
      size_t used = 0;
      v.push_back(std::stod(item, &used));
      if (used != item.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw InputError(what + ": '" + quoteForMessage(spec_in) + expected);
    }
  }
  if (v.size() != 4 && v.size() != 6 && v.size() != 11)
    throw InputError(what + ": '" + quoteForMessage(spec_in) + expected);
  if (const auto problem = cameraValuesProblem(v))
    throw InputError(what + ": '" + quoteForMessage(spec_in) + "': " + *problem);
  return cameraModelFromValues(v);
}

}  // namespace ff
