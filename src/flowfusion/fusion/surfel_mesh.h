#pragma once
// Triangle mesh of the stable surfels, made without rendering: each surfel writes the signed
// distance to its own plane into the voxels around it (a sparse TSDF of 4x4x4-voxel blocks,
// weighted by confidence and by the lateral distance to the surfel), and marching cubes extracts
// the zero level. Cost and memory grow with the map's surface, not with the number of views:
// the re-rendered keyframes integrated into an Open3D ScalableTSDFVolume it replaces took a minute
// and a gigabyte at the end of a 600-frame run (docs/performance.md#export).
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "flowfusion/fusion/static_map.h"

namespace ff {

struct SurfelMesh {
  std::vector<Eigen::Vector3f> vertices;          // world, metres
  std::vector<std::array<uint8_t, 3>> colors;     // RGB
  std::vector<std::array<int32_t, 3>> triangles;  // vertex indices, counter-clockwise seen from the front
};

// Surfels with confidence >= stable_confidence, voxels of voxel_m; signed distances are clamped to
// +-truncation_m. Deterministic: the same surfels give the same mesh, vertex for vertex.
SurfelMesh meshSurfels(const std::vector<Surfel>& surfels, double stable_confidence, double voxel_m,
                       double truncation_m);

// Binary little-endian PLY (float x y z, uchar red green blue; uchar-int vertex_indices), as the
// bytes of the file.
std::string plyBytes(const SurfelMesh& mesh);

}  // namespace ff
