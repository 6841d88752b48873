#include "flowfusion/visualization/map_preview.h"

#include <algorithm>
#include <filesystem>

#include "flowfusion/core/atomic_file.h"
#include "flowfusion/core/error.h"

namespace ff {

namespace {

// Camera at `eye` looking at `target`; `up` is the world direction that appears upwards.
SE3 lookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target, const Eigen::Vector3d& up) {
  const Eigen::Vector3d z = (target - eye).normalized();
  Eigen::Vector3d x = z.cross(up);
  if (x.norm() < 1e-6) x = z.unitOrthogonal();
  x.normalize();
  const Eigen::Vector3d y = z.cross(x);
  SE3 T_world_cam = SE3::Identity();
  T_world_cam.linear().col(0) = x;
  T_world_cam.linear().col(1) = y;
  T_world_cam.linear().col(2) = z;
  T_world_cam.translation() = eye;
  return T_world_cam;
}

}  // namespace

cv::Mat renderPreview(const StaticMap& map, const SE3& T_world_cam, const CameraIntrinsics& camera) {
  const ModelPrediction pred = map.predict(T_world_cam, camera);
  cv::Mat out = cv::Mat::zeros(camera.height, camera.width, CV_8UC3);
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      if (pred.depth.at<float>(y, x) <= 0) continue;
      const cv::Vec3f n = pred.normal.at<cv::Vec3f>(y, x);
      const Eigen::Vector3f ray = Eigen::Vector3f(static_cast<float>((x - camera.cx) / camera.fx),
                                                  static_cast<float>((y - camera.cy) / camera.fy), 1.0f)
                                      .normalized();
      const float shade = 0.35f + 0.65f * std::abs(ray.dot(Eigen::Vector3f(n[0], n[1], n[2])));
      const cv::Vec3b c = pred.color.at<cv::Vec3b>(y, x);
      out.at<cv::Vec3b>(y, x) = cv::Vec3b(cv::saturate_cast<uchar>(c[0] * shade), cv::saturate_cast<uchar>(c[1] * shade),
                                          cv::saturate_cast<uchar>(c[2] * shade));
    }
  return out;
}

std::vector<std::string> writePreviews(const StaticMap& map, const std::string& dir) {
  const MapPoints pts = map.points();
  if (pts.positions.empty() || map.keyframePoses().empty())
    throw InputError("cannot write previews to '" + dir + "': the map holds no stable surfels");
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw InputError("cannot create preview folder '" + dir + "': " + ec.message());

  // Orbit around the median map point (robust to stray surfels), at the first keyframe's distance,
  // with the first keyframe's "up" (camera y points down).
  std::vector<float> xs, ys, zs;
  for (const auto& p : pts.positions) {
    xs.push_back(p.x());
    ys.push_back(p.y());
    zs.push_back(p.z());
  }
  auto median = [](std::vector<float>& v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return static_cast<double>(v[v.size() / 2]);
  };
  const Eigen::Vector3d centre(median(xs), median(ys), median(zs));
  const SE3& first = map.keyframePoses().front();
  const Eigen::Vector3d up = -first.linear().col(1);
  const Eigen::Vector3d offset = first.translation() - centre;
  const CameraIntrinsics camera = map.keyframeCamera();

  std::vector<SE3> views = {first};
  for (double deg : {-35.0, 35.0}) {
    const Eigen::AngleAxisd turn(deg * M_PI / 180.0, up);
    views.push_back(lookAt(centre + turn * offset, centre, up));
  }
  const Eigen::Vector3d side = offset.cross(up).normalized();
  views.push_back(lookAt(centre + Eigen::AngleAxisd(-30.0 * M_PI / 180.0, side) * offset, centre, up));

  std::vector<std::string> paths;
  for (size_t k = 0; k < views.size(); ++k) {
    const std::string path = (std::filesystem::path(dir) / ("preview_" + std::to_string(k) + ".png")).string();
    writePngAtomic(path, renderPreview(map, views[k], camera), "map preview");
    paths.push_back(path);
  }
  return paths;
}

}  // namespace ff
