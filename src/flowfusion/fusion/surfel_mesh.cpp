#include "flowfusion/fusion/surfel_mesh.h"

// Open3D's marching-cubes tables (edge_table, tri_table, shift, edge_shift, edge_to_vert).
#include <open3d/pipelines/integration/MarchingCubesConst.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <deque>
#include <unordered_map>

namespace ff {

namespace {

static_assert(std::endian::native == std::endian::little, "plyBytes writes the host's floats as little-endian");

constexpr int kBlock = 4;  // voxels per block side
// Grid coordinates are packed 20 bits per axis (edge keys add 2 bits for the axis); surfels farther
// than kMaxGrid voxels from the origin (2.6 km at 1 cm) are left out.
constexpr int64_t kCoordOffset = int64_t{1} << 19;
constexpr float kMaxGrid = static_cast<float>(int64_t{1} << 18);
// A surfel writes the 4x4x4 grid points around it whose lateral distance to it (along its plane)
// is below this many voxels; its weight falls off quadratically to 0 there.
constexpr float kReachVoxels = 2.0f;

struct Voxel {
  float sdf_sum = 0;  // weighted signed distances, metres (positive in front of the surface)
  float weight = 0;
  float rgb_sum[3] = {0, 0, 0};
};
using Block = std::array<Voxel, kBlock * kBlock * kBlock>;

uint64_t pack(const Eigen::Vector3i& c) {
  return (static_cast<uint64_t>(c.x() + kCoordOffset) << 40) | (static_cast<uint64_t>(c.y() + kCoordOffset) << 20) |
         static_cast<uint64_t>(c.z() + kCoordOffset);
}
Eigen::Vector3i unpack(uint64_t key) {
  const auto axis = [key](int shift) { return static_cast<int>(static_cast<int64_t>((key >> shift) & 0xfffff) - kCoordOffset); };
  return {axis(40), axis(20), axis(0)};
}
int floorDiv(int a) { return a >= 0 ? a / kBlock : -((-a + kBlock - 1) / kBlock); }
int localIndex(const Eigen::Vector3i& g, const Eigen::Vector3i& block) {
  const Eigen::Vector3i l = g - kBlock * block;
  return (l.z() * kBlock + l.y()) * kBlock + l.x();
}

// Voxels in blocks allocated where surfels are; the last block written is cached (a surfel's
// neighbourhood mostly falls into it).
class SparseTsdf {
 public:
  Voxel& at(const Eigen::Vector3i& g) {
    const Eigen::Vector3i b(floorDiv(g.x()), floorDiv(g.y()), floorDiv(g.z()));
    const uint64_t key = pack(b);
    if (key != cached_key_ || !cached_) {
      const auto [it, added] = index_.try_emplace(key, blocks_.size());
      if (added) blocks_.emplace_back();
      cached_key_ = key;
      cached_ = &blocks_[it->second];
    }
    return (*cached_)[localIndex(g, b)];
  }
  const Block* findBlock(const Eigen::Vector3i& b) const {
    const auto it = index_.find(pack(b));
    return it == index_.end() ? nullptr : &blocks_[it->second];
  }
  // Block coordinates in increasing key order (the mesh's vertex order must not depend on hashing).
  std::vector<Eigen::Vector3i> sortedBlocks() const {
    std::vector<uint64_t> keys;
    keys.reserve(index_.size());
    for (const auto& entry : index_) keys.push_back(entry.first);
    std::sort(keys.begin(), keys.end());
    std::vector<Eigen::Vector3i> out;
    out.reserve(keys.size());
    for (uint64_t key : keys) out.push_back(unpack(key));
    return out;
  }

 private:
  std::unordered_map<uint64_t, size_t> index_;
  std::deque<Block> blocks_;  // stable addresses
  uint64_t cached_key_ = 0;
  Block* cached_ = nullptr;
};

void integrateSurfel(SparseTsdf& tsdf, const Surfel& s, float voxel, float truncation) {
  const Eigen::Vector3f q = s.position / voxel;  // grid units
  if (!q.allFinite() || q.cwiseAbs().maxCoeff() > kMaxGrid) return;
  const Eigen::Vector3i base(static_cast<int>(std::floor(q.x())), static_cast<int>(std::floor(q.y())),
                             static_cast<int>(std::floor(q.z())));
  const float reach2 = kReachVoxels * kReachVoxels;
  const float rgb[3] = {s.bgr[2], s.bgr[1], s.bgr[0]};
  for (int dz = -1; dz <= 2; ++dz)
    for (int dy = -1; dy <= 2; ++dy)
      for (int dx = -1; dx <= 2; ++dx) {
        const Eigen::Vector3i g = base + Eigen::Vector3i(dx, dy, dz);
        const Eigen::Vector3f r = g.cast<float>() - q;
        const float along = s.normal.dot(r);
        const float lateral2 = r.squaredNorm() - along * along;
        if (lateral2 >= reach2) continue;
        const float w = s.confidence * (1.0f - lateral2 / reach2);
        Voxel& v = tsdf.at(g);
        v.sdf_sum += w * std::clamp(along * voxel, -truncation, truncation);
        v.weight += w;
        for (int c = 0; c < 3; ++c) v.rgb_sum[c] += w * rgb[c];
      }
}

// Marching cubes over every cube whose eight corners carry weight; a vertex per crossed grid edge,
// shared between the cubes around it. A block's cubes reach into the 7 blocks above it, looked up
// once per block.
class CubeMarcher {
 public:
  CubeMarcher(const SparseTsdf& tsdf, float voxel, SurfelMesh& mesh) : tsdf_(tsdf), voxel_(voxel), mesh_(mesh) {}

  void block(const Eigen::Vector3i& b) {
    for (int n = 0; n < 8; ++n) neighbour_[n] = tsdf_.findBlock(b + Eigen::Vector3i(n & 1, (n >> 1) & 1, n >> 2));
    for (int z = 0; z < kBlock; ++z)
      for (int y = 0; y < kBlock; ++y)
        for (int x = 0; x < kBlock; ++x) cube(b, Eigen::Vector3i(x, y, z));
  }

 private:
  void cube(const Eigen::Vector3i& b, const Eigen::Vector3i& local) {
    const Eigen::Vector3i origin = kBlock * b + local;
    const Voxel* corner[8];
    float f[8];
    int index = 0;
    for (int i = 0; i < 8; ++i) {
      const Eigen::Vector3i l = local + shift[i];
      const Block* block = neighbour_[(l.x() / kBlock) + 2 * (l.y() / kBlock) + 4 * (l.z() / kBlock)];
      if (!block) return;
      corner[i] = &(*block)[((l.z() % kBlock) * kBlock + l.y() % kBlock) * kBlock + l.x() % kBlock];
      if (corner[i]->weight <= 0) return;
      f[i] = corner[i]->sdf_sum / corner[i]->weight;
      if (f[i] < 0) index |= 1 << i;
    }
    if (edge_table[index] == 0) return;
    int32_t vertex[12];
    for (int e = 0; e < 12; ++e)
      if (edge_table[index] & (1 << e)) vertex[e] = edgeVertex(origin, e, corner, f);
    for (int i = 0; tri_table[index][i] != -1; i += 3)
      mesh_.triangles.push_back({vertex[tri_table[index][i]], vertex[tri_table[index][i + 2]],
                                 vertex[tri_table[index][i + 1]]});
  }

  int32_t edgeVertex(const Eigen::Vector3i& origin, int e, const Voxel* const* corner, const float* f) {
    const Eigen::Vector3i start = origin + edge_shift[e].head<3>();
    const uint64_t key = (pack(start) << 2) | static_cast<uint64_t>(edge_shift[e](3));
    const auto [it, added] = vertex_of_edge_.try_emplace(key, static_cast<int32_t>(mesh_.vertices.size()));
    if (!added) return it->second;
    const int a = edge_to_vert[e][0], b = edge_to_vert[e][1];
    const float t = f[a] / (f[a] - f[b]);
    const Eigen::Vector3f pa = (origin + shift[a]).cast<float>(), pb = (origin + shift[b]).cast<float>();
    mesh_.vertices.push_back((pa + t * (pb - pa)) * voxel_);
    std::array<uint8_t, 3> rgb;
    for (int c = 0; c < 3; ++c) {
      const float ca = corner[a]->rgb_sum[c] / corner[a]->weight, cb = corner[b]->rgb_sum[c] / corner[b]->weight;
      rgb[c] = static_cast<uint8_t>(std::clamp(std::lround(ca + t * (cb - ca)), 0L, 255L));
    }
    mesh_.colors.push_back(rgb);
    return it->second;
  }

  const SparseTsdf& tsdf_;
  const Block* neighbour_[8] = {};
  float voxel_;
  SurfelMesh& mesh_;
  std::unordered_map<uint64_t, int32_t> vertex_of_edge_;
};

template <class T>
void append(std::string& out, const T& value) {
  out.append(reinterpret_cast<const char*>(&value), sizeof(T));
}

}  // namespace

SurfelMesh meshSurfels(const std::vector<Surfel>& surfels, double stable_confidence, double voxel_m,
                       double truncation_m) {
  SparseTsdf tsdf;
  const float voxel = static_cast<float>(voxel_m), truncation = static_cast<float>(truncation_m);
  for (const Surfel& s : surfels)
    if (s.confidence >= stable_confidence) integrateSurfel(tsdf, s, voxel, truncation);
  SurfelMesh mesh;
  CubeMarcher marcher(tsdf, voxel, mesh);
  for (const Eigen::Vector3i& block : tsdf.sortedBlocks()) marcher.block(block);
  return mesh;
}

std::string plyBytes(const SurfelMesh& mesh) {
  std::string out =
      "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(mesh.vertices.size()) +
      "\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty uchar green\n"
      "property uchar blue\nelement face " +
      std::to_string(mesh.triangles.size()) + "\nproperty list uchar int vertex_indices\nend_header\n";
  out.reserve(out.size() + mesh.vertices.size() * 15 + mesh.triangles.size() * 13);
  for (size_t k = 0; k < mesh.vertices.size(); ++k) {
    for (int c = 0; c < 3; ++c) append(out, mesh.vertices[k](c));
    for (int c = 0; c < 3; ++c) append(out, mesh.colors[k][c]);
  }
  for (const auto& triangle : mesh.triangles) {
    append(out, uint8_t{3});
    for (int32_t index : triangle) append(out, index);
  }
  return out;
}

}  // namespace ff
