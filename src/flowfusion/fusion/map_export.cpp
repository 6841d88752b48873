// PLY export through Open3D's legacy I/O (binary PLY, read by Open3D and MeshLab).
#include <open3d/geometry/Image.h>
#include <open3d/geometry/PointCloud.h>
#include <open3d/geometry/RGBDImage.h>
#include <open3d/geometry/TriangleMesh.h>
#include <open3d/io/PointCloudIO.h>
#include <open3d/io/TriangleMeshIO.h>
#include <open3d/pipelines/integration/ScalableTSDFVolume.h>

#include "flowfusion/core/atomic_file.h"
#include "flowfusion/core/error.h"
#include "flowfusion/fusion/static_map.h"

namespace ff {

namespace {

Eigen::Vector3d rgbFromBgr(const cv::Vec3b& bgr) { return Eigen::Vector3d(bgr[2], bgr[1], bgr[0]) / 255.0; }

}  // namespace

void StaticMap::exportPointCloud(const std::string& path) const {
  const MapPoints pts = points();
  if (pts.positions.empty()) throw InputError("cannot write point cloud '" + path + "': the map holds no stable surfels");
  open3d::geometry::PointCloud cloud;
  cloud.points_.reserve(pts.positions.size());
  for (size_t k = 0; k < pts.positions.size(); ++k) {
    cloud.points_.push_back(pts.positions[k].cast<double>());
    cloud.normals_.push_back(pts.normals[k].cast<double>());
    cloud.colors_.push_back(rgbFromBgr(pts.colors[k]));
  }
  // Open3D does not check its own writes: the file must read back whole before it is renamed.
  writeThroughTempPath(
      path,
      [&](const std::string& temp) {
        open3d::geometry::PointCloud back;
        return open3d::io::WritePointCloud(temp, cloud) && open3d::io::ReadPointCloud(temp, back) &&
               back.points_.size() == cloud.points_.size();
      },
      "point cloud");
}

void StaticMap::exportMesh(const std::string& path) const {
  // The model's own predictions at the keyframes go through a TSDF: the mesh then holds exactly
  // the static surfaces of the map, closed between surfels. Half resolution is enough for
  // voxels of a centimetre and keeps the export to about a second.
  if (keyframes_.empty() || points().positions.empty())
    throw InputError("cannot write mesh '" + path + "': the map holds no stable surfels");
  const CameraIntrinsics camera = keyframe_camera_.atLevel(1);
  const open3d::camera::PinholeCameraIntrinsic intrinsic(camera.width, camera.height, camera.fx, camera.fy,
                                                         camera.cx, camera.cy);
  open3d::pipelines::integration::ScalableTSDFVolume volume(
      config_.mesh_voxel_m, config_.mesh_truncation_m, open3d::pipelines::integration::TSDFVolumeColorType::RGB8);
  for (const SE3& T_world_cam : keyframes_) {
    const ModelPrediction pred = predict(T_world_cam, camera);
    open3d::geometry::Image color, depth;
    color.Prepare(camera.width, camera.height, 3, 1);
    depth.Prepare(camera.width, camera.height, 1, 2);
    for (int y = 0; y < camera.height; ++y)
      for (int x = 0; x < camera.width; ++x) {
        const cv::Vec3b bgr = pred.color.at<cv::Vec3b>(y, x);
        uint8_t* c = color.PointerAt<uint8_t>(x, y, 0);
        c[0] = bgr[2];
        c[1] = bgr[1];
        c[2] = bgr[0];
        *depth.PointerAt<uint16_t>(x, y) = static_cast<uint16_t>(std::lround(pred.depth.at<float>(y, x) * 1000.0f));
      }
    const auto rgbd = open3d::geometry::RGBDImage::CreateFromColorAndDepth(color, depth, 1000.0,
                                                                           config_.max_depth_m + 1.0, false);
    volume.Integrate(*rgbd, intrinsic, T_world_cam.inverse().matrix());
  }
  const auto mesh = volume.ExtractTriangleMesh();
  if (mesh->triangles_.empty()) throw InputError("cannot write mesh '" + path + "': the map gave no triangles");
  writeThroughTempPath(
      path,
      [&](const std::string& temp) {
        open3d::geometry::TriangleMesh back;
        return open3d::io::WriteTriangleMesh(temp, *mesh) && open3d::io::ReadTriangleMesh(temp, back) &&
               back.vertices_.size() == mesh->vertices_.size() && back.triangles_.size() == mesh->triangles_.size();
      },
      "mesh");
}

}  // namespace ff
