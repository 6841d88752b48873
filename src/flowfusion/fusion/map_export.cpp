// PLY exports (binary, read by Open3D and MeshLab), each file assembled in memory and written atomically.
#include <algorithm>
#include <string>

#include "flowfusion/core/atomic_file.h"
#include "flowfusion/core/error.h"
#include "flowfusion/fusion/static_map.h"
#include "flowfusion/fusion/surfel_mesh.h"

namespace ff {

namespace {

template <class T>
void append(std::string& out, T value) {
  out.append(reinterpret_cast<const char*>(&value), sizeof(T));
}

// Open3D's colour byte: the colour in [0, 1] times 255, truncated (as its PLY writer stores it).
uint8_t open3dColorByte(float channel) {
  return static_cast<uint8_t>(std::min(255.0, std::max(0.0, channel / 255.0 * 255.0)));
}

}  // namespace

void StaticMap::exportPointCloud(const std::string& path) const {
  // Written here in the layout (and with the bytes) Open3D's PLY writer gives, without its three
  // double-precision copies of the cloud and the read-back of the whole file.
  const MapPoints pts = points();
  if (pts.positions.empty()) throw InputError("cannot write point cloud '" + path + "': the map holds no stable surfels");
  std::string out = "ply\nformat binary_little_endian 1.0\ncomment Created by Open3D\nelement vertex " +
                    std::to_string(pts.positions.size()) +
                    "\nproperty double x\nproperty double y\nproperty double z\nproperty double nx\n"
                    "property double ny\nproperty double nz\nproperty uchar red\nproperty uchar green\n"
                    "property uchar blue\nend_header\n";
  out.reserve(out.size() + pts.positions.size() * (6 * sizeof(double) + 3));
  for (size_t k = 0; k < pts.positions.size(); ++k) {
    for (int c = 0; c < 3; ++c) append(out, static_cast<double>(pts.positions[k](c)));
    for (int c = 0; c < 3; ++c) append(out, static_cast<double>(pts.normals[k](c)));
    for (int c = 2; c >= 0; --c) append(out, open3dColorByte(pts.colors[k][c]));
  }
  writeFileAtomic(path, out, "point cloud");
}

void StaticMap::exportMesh(const std::string& path) const {
  // The stable surfels' own planes through a sparse TSDF (surfel_mesh.h): the mesh holds exactly
  // the static surfaces of the map, closed between surfels, without rendering any view.
  if (!hasStableSurfels())
    throw InputError("cannot write mesh '" + path + "': the map holds no stable surfels");
  const SurfelMesh mesh = meshSurfels(surfels_, config_.stable_confidence, config_.mesh_voxel_m, config_.mesh_truncation_m);
  if (mesh.triangles.empty()) throw InputError("cannot write mesh '" + path + "': the map gave no triangles");
  writeFileAtomic(path, plyBytes(mesh), "mesh");
}

}  // namespace ff
