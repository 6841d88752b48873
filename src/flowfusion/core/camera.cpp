#include "flowfusion/core/camera.h"

#include <sstream>
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

CameraIntrinsics parseCamera(const std::string& spec_in, const std::string& what) {
  std::string spec;
  for (char ch : spec_in)
    if (ch != ' ' && ch != '\t' && ch != '\n' && ch != '\r') spec += ch;
  if (spec == "fr1" || spec == "fr2" || spec == "fr3") return *freiburgPreset(spec[2] - '0');
  std::vector<double> v;
  std::stringstream ss(spec);
  std::string item;
  while (std::getline(ss, item, ',')) {
    try {
      size_t used = 0;
      v.push_back(std::stod(item, &used));
      if (used != item.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw InputError(what + ": '" + spec_in + "' is not fr1, fr2, fr3 or fx,fy,cx,cy[,width,height]");
    }
  }
  if (v.size() != 4 && v.size() != 6)
    throw InputError(what + ": '" + spec_in + "' is not fr1, fr2, fr3 or fx,fy,cx,cy[,width,height]");
  CameraIntrinsics c{v[0], v[1], v[2], v[3], 640, 480};
  if (v.size() == 6) {
    c.width = static_cast<int>(v[4]);
    c.height = static_cast<int>(v[5]);
  }
  if (!c.valid()) throw InputError(what + ": '" + spec_in + "' has a non-positive focal length or size");
  return c;
}

}  // namespace ff
