#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <open3d/geometry/PointCloud.h>
#include <open3d/geometry/TriangleMesh.h>
#include <open3d/io/PointCloudIO.h>
#include <open3d/io/TriangleMeshIO.h>

#include "flowfusion/core/error.h"
#include "flowfusion/fusion/static_map.h"
#include "room_fixture.h"
#include "testing/test_util.h"

namespace ff {
namespace {

using testing::RoomFixture;

cv::Mat staticWeight(const cv::Mat& mask) {
  cv::Mat w;
  mask.convertTo(w, CV_32F, -1.0 / 255.0, 1.0);
  return w;
}

StaticMap fuse(const RoomFixture& room, bool use_masks, const FusionConfig& config = {}) {
  StaticMap map(config);
  for (int i = 0; i < room.frames; ++i) {
    const auto v = room.render(i);
    map.integrate(v.frame, room.camera, room.pose(i), use_masks ? staticWeight(v.mask) : cv::Mat());
  }
  return map;
}

double median(std::vector<double> v) {
  if (v.empty()) return 1e9;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// Fraction of map points inside the volume the sphere swept, leaving out its positions from frame
// `recent` on (the last frames legitimately see the sphere there, and free space needs a few frames
// of evidence before it removes a surfel).
double ghostFraction(const StaticMap& map, const RoomFixture& room, int recent) {
  const MapPoints pts = map.points();
  size_t ghosts = 0;
  for (const auto& p : pts.positions) {
    const Eigen::Vector3d q = p.cast<double>();
    bool current = false;
    for (int i = recent; i < room.frames && !current; ++i)
      current = (q - room.sphereCentre(i)).norm() < room.sphere_radius_m + 0.03;
    if (!current && room.distanceToSweep(q) < room.sphere_radius_m + 0.01) ++ghosts;
  }
  return pts.positions.empty() ? 1.0 : static_cast<double>(ghosts) / pts.positions.size();
}

TEST(StaticMap, StaticRoomSurfacesWithinMillimetres) {
  RoomFixture room;
  const StaticMap map = fuse(room, false);
  const MapPoints pts = map.points();
  ASSERT_GT(pts.positions.size(), 10000u);
  double sum = 0, worst = 0;
  for (const auto& p : pts.positions) {
    const double d = room.distanceToRoom(p.cast<double>());
    sum += d;
    worst = std::max(worst, d);
  }
  const double mean = sum / pts.positions.size();
  std::printf("static room: %zu surfels (%zu stable), mean distance %.2f mm, max %.2f mm\n", map.size(),
              pts.positions.size(), mean * 1e3, worst * 1e3);
  EXPECT_LT(mean, 0.01);
  EXPECT_LT(mean, 0.003);  // exact data: only the surfel discretisation remains
  ASSERT_EQ(pts.colors.size(), pts.positions.size());
  ASSERT_EQ(pts.normals.size(), pts.positions.size());
}

TEST(StaticMap, PredictionReproducesDepthAtFusedPoseAndCoarserLevel) {
  RoomFixture room;
  room.frames = 12;
  const StaticMap map = fuse(room, false);
  for (int level : {0, 1}) {
    const CameraIntrinsics cam = room.camera.atLevel(level);
    const SE3 pose = room.pose(room.frames - 1);
    const auto truth = room.render(pose, cam, -1);
    const ModelPrediction pred = map.predict(pose, cam);
    ASSERT_EQ(pred.depth.size(), truth.frame.depth.size());
    ASSERT_EQ(pred.intensity.type(), CV_32FC1);
    ASSERT_EQ(pred.color.type(), CV_8UC3);
    std::vector<double> depth_err, intensity_err;
    for (int y = 0; y < cam.height; ++y)
      for (int x = 0; x < cam.width; ++x) {
        const float zp = pred.depth.at<float>(y, x);
        if (zp <= 0) continue;
        depth_err.push_back(std::abs(zp - truth.frame.depth.at<float>(y, x)));
        intensity_err.push_back(std::abs(pred.intensity.at<float>(y, x) - truth.frame.intensity.at<float>(y, x)));
      }
    const double coverage = static_cast<double>(depth_err.size()) / (cam.width * cam.height);
    std::printf("level %d: coverage %.3f, median |depth diff| %.2f mm, median |intensity diff| %.4f\n", level,
                coverage, median(depth_err) * 1e3, median(intensity_err));
    EXPECT_GT(coverage, 0.95);
    EXPECT_LT(median(depth_err), 0.01);
    EXPECT_LT(median(intensity_err), 0.05);
  }
}

TEST(StaticMap, DepthOnlyPredictionMatchesTheTruthAndTheRayTracedOne) {
  RoomFixture room;
  room.frames = 12;
  const StaticMap map = fuse(room, false);
  const CameraIntrinsics cam = room.camera.atLevel(1);
  const SE3 pose = room.pose(room.frames - 1);
  const auto truth = room.render(pose, cam, -1);
  const cv::Mat fast = map.predictDepth(pose, cam);
  const ModelPrediction full = map.predict(pose, cam);
  ASSERT_EQ(fast.type(), CV_32FC1);
  ASSERT_EQ(fast.size(), full.depth.size());
  std::vector<double> err, diff;
  int drawn = 0, traced = 0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      const float zf = fast.at<float>(y, x), zr = full.depth.at<float>(y, x);
      traced += zr > 0;
      if (zf <= 0) continue;
      ++drawn;
      err.push_back(std::abs(zf - truth.frame.depth.at<float>(y, x)));
      if (zr > 0) diff.push_back(std::abs(zf - zr));
    }
  const double coverage = static_cast<double>(drawn) / traced;
  std::printf("depth-only prediction: coverage %.3f of the ray-traced one, median |depth - truth| %.2f mm, "
              "median |depth - ray-traced| %.2f mm\n",
              coverage, median(err) * 1e3, median(diff) * 1e3);
  // Measured: coverage 0.93, 0.00 mm and 0.00 mm: the small squares leave some pixels between
  // surfels empty (the pipeline fills them with the frame's own depth).
  EXPECT_GT(coverage, 0.9);
  EXPECT_LT(median(err), 0.002);
  EXPECT_LT(median(diff), 0.002);
  EXPECT_THROW(map.predictDepth(pose, CameraIntrinsics{}), InputError);
}

TEST(StaticMap, StableDepthMatchesTheRayTracedPredictionAndLeavesOutUnstableSurfels) {
  RoomFixture room;
  room.frames = 12;
  const StaticMap map = fuse(room, false);
  const CameraIntrinsics cam = room.camera.atLevel(1);
  const SE3 pose = room.pose(room.frames - 1);
  const cv::Mat fast = map.predictStableDepth(pose, cam);
  const ModelPrediction full = map.predict(pose, cam);
  ASSERT_EQ(fast.type(), CV_32FC1);
  ASSERT_EQ(fast.size(), full.depth.size());
  std::vector<double> rel_err;
  int both = 0, only_full = 0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      const float zf = fast.at<float>(y, x), zr = full.depth.at<float>(y, x);
      if (zr > 0 && zf > 0) {
        ++both;
        rel_err.push_back(std::abs(zf - zr) / zr);
      } else if (zr > 0) {
        ++only_full;
      }
    }
  const double coverage = static_cast<double>(both) / (both + only_full);
  std::sort(rel_err.begin(), rel_err.end());
  const double p95 = rel_err[rel_err.size() * 95 / 100], p99 = rel_err[rel_err.size() * 99 / 100];
  std::printf("stable depth: coverage %.3f of the ray-traced one, |diff| / depth median %.4f, p95 %.4f, p99 %.4f\n",
              coverage, median(rel_err), p95, p99);
  EXPECT_GT(coverage, 0.97);
  EXPECT_LT(p95, 0.01);  // the segmentation's margins are 1 % (agreement) and 3 % (occlusion)

  // One frame fused into an empty map: nothing is stable yet, so nothing is drawn.
  StaticMap fresh;
  const auto v = room.render(0);
  fresh.integrate(v.frame, room.camera, room.pose(0));
  EXPECT_GT(fresh.size(), 0u);
  EXPECT_EQ(cv::countNonZero(fresh.predictStableDepth(room.pose(0), cam)), 0);
  EXPECT_GT(cv::countNonZero(fresh.predict(room.pose(0), cam).depth), 0);
}

TEST(StaticMap, SurfacesSeenAsDynamicLeaveTheMap) {
  // A static room fused for a while, then seen twice with every pixel weighted as dynamic (what
  // the segmentation says once an object fused by mistake starts to move).
  RoomFixture room;
  room.frames = 10;
  StaticMap map = fuse(room, false);
  const size_t before = map.points().positions.size();
  const auto v = room.render(room.frames - 1);
  const cv::Mat dynamic = cv::Mat::zeros(v.frame.depth.size(), CV_32F);
  FusionConfig off;
  off.dynamic_removal = false;
  for (int k = 0; k < off.free_space_votes; ++k) map.integrate(v.frame, room.camera, room.pose(room.frames - 1), dynamic);
  const size_t after = map.points().positions.size();
  std::printf("surfels seen as dynamic: %zu stable before, %zu after\n", before, after);
  EXPECT_LT(after, before / 2);  // the part of the room in view is gone

  StaticMap unchanged(off);
  for (int i = 0; i < room.frames; ++i) unchanged.integrate(room.render(i).frame, room.camera, room.pose(i));
  const size_t unchanged_before = unchanged.points().positions.size();
  for (int k = 0; k < off.free_space_votes; ++k)
    unchanged.integrate(v.frame, room.camera, room.pose(room.frames - 1), dynamic);
  EXPECT_EQ(unchanged.points().positions.size(), unchanged_before);
}

TEST(StaticMap, MaskedMovingObjectLeavesNoGhostAndBackgroundFillsIn) {
  RoomFixture room;
  room.with_sphere = true;
  const StaticMap map = fuse(room, true);
  const double ghosts = ghostFraction(map, room, room.frames);
  std::printf("with masks: ghost fraction %.5f of %zu points\n", ghosts, map.points().positions.size());
  EXPECT_LE(ghosts, 0.01);

  // Where the sphere stood at frame 0, the wall behind it is now in the map.
  const auto first = room.render(0);
  const ModelPrediction pred = map.predict(room.pose(0), room.camera);
  const auto wall = room.render(room.pose(0), room.camera, -1);
  int hidden = 0, filled = 0;
  for (int y = 0; y < room.camera.height; ++y)
    for (int x = 0; x < room.camera.width; ++x) {
      if (!first.mask.at<uchar>(y, x)) continue;
      ++hidden;
      const float z = pred.depth.at<float>(y, x);
      if (z > 0 && std::abs(z - wall.frame.depth.at<float>(y, x)) < 0.02) ++filled;
    }
  ASSERT_GT(hidden, 100);
  std::printf("background behind the first sphere position: %.3f filled\n", static_cast<double>(filled) / hidden);
  EXPECT_GT(filled, 0.9 * hidden);
}

TEST(StaticMap, FreeSpaceRemovesGhostsWithoutMasks) {
  RoomFixture room;
  room.with_sphere = true;
  const StaticMap carved = fuse(room, false);
  FusionConfig no_carving;
  no_carving.free_space_votes = 1000000;
  no_carving.unstable_window_frames = 1000000;
  const StaticMap kept = fuse(room, false, no_carving);
  // Free space needs free_space_votes frames that see through a surfel, so the last few positions
  // of the sphere may still be in the map.
  const int recent = room.frames - 1 - FusionConfig{}.free_space_votes - 1;
  const double with = ghostFraction(carved, room, recent), without = ghostFraction(kept, room, recent);
  std::printf("without masks: ghost fraction %.5f with free-space removal, %.5f without any removal\n", with,
              without);
  for (int k : {1, 3, 6}) std::printf("  leaving out the last %d positions: %.5f\n", k, ghostFraction(carved, room, room.frames - k));
  EXPECT_GT(without, 0.02);
  EXPECT_LT(with, 0.01);
}

TEST(StaticMap, ExportedFilesLoadInOpen3d) {
  RoomFixture room;
  room.frames = 10;
  FusionConfig config;
  config.mesh_voxel_m = 0.03;  // coarse: keeps the test fast
  config.mesh_truncation_m = 0.1;
  const StaticMap map = fuse(room, false, config);
  testing::TempDir dir;
  const std::string mesh_path = dir.str() + "/map.ply", cloud_path = dir.str() + "/map_points.ply";
  map.exportMesh(mesh_path);
  map.exportPointCloud(cloud_path);

  open3d::geometry::TriangleMesh mesh;
  ASSERT_TRUE(open3d::io::ReadTriangleMesh(mesh_path, mesh));
  EXPECT_GT(mesh.triangles_.size(), 1000u);
  EXPECT_TRUE(mesh.HasVertexColors());
  EXPECT_LT(room.meanDistanceToRoom(mesh.vertices_), 0.015);

  open3d::geometry::PointCloud cloud;
  ASSERT_TRUE(open3d::io::ReadPointCloud(cloud_path, cloud));
  EXPECT_EQ(cloud.points_.size(), map.points().positions.size());
  EXPECT_TRUE(cloud.HasColors());
  EXPECT_TRUE(cloud.HasNormals());
}

TEST(StaticMap, MeshAtCentimetreVoxelsLiesOnTheRoomFacesTheCameraAndRepeats) {
  RoomFixture room;
  room.frames = 10;
  const StaticMap map = fuse(room, false);
  testing::TempDir dir;
  const std::string path = dir.str() + "/map.ply", again = dir.str() + "/again.ply";
  map.exportMesh(path);
  map.exportMesh(again);
  open3d::geometry::TriangleMesh mesh;
  ASSERT_TRUE(open3d::io::ReadTriangleMesh(path, mesh));
  ASSERT_GT(mesh.triangles_.size(), 10000u);
  EXPECT_LT(room.meanDistanceToRoom(mesh.vertices_), 0.003);  // exact data: the surfels' own error and the voxels'
  // Seen from inside, every wall's front faces the camera.
  const Eigen::Vector3d camera = room.pose(0).translation();
  size_t facing = 0;
  for (const Eigen::Vector3i& t : mesh.triangles_) {
    const Eigen::Vector3d a = mesh.vertices_[t(0)], b = mesh.vertices_[t(1)], c = mesh.vertices_[t(2)];
    if ((b - a).cross(c - a).dot(camera - a) > 0) ++facing;
  }
  EXPECT_GT(facing, 0.99 * mesh.triangles_.size());
  const auto bytes = [](const std::string& file) {
    std::ifstream in(file, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  EXPECT_EQ(bytes(path), bytes(again));
}

TEST(StaticMap, MemoryBudgetStopsGrowthWithAFlag) {
  RoomFixture room;
  room.frames = 6;
  FusionConfig config;
  config.max_surfels = 2000;
  const StaticMap map = fuse(room, false, config);
  EXPECT_TRUE(map.budgetReached());
  EXPECT_LE(map.size(), 2000u);
  const StaticMap roomy = fuse(room, false);
  EXPECT_FALSE(roomy.budgetReached());
}

TEST(StaticMap, RejectsBadInputAndConfig) {
  RoomFixture room;
  StaticMap map;
  const auto v = room.render(0);
  CameraIntrinsics wrong = room.camera;
  wrong.width = 640;
  EXPECT_THROW(map.integrate(v.frame, wrong, room.pose(0)), InputError);
  EXPECT_THROW(map.integrate(v.frame, room.camera, room.pose(0), cv::Mat::ones(10, 10, CV_32F)), InputError);
  EXPECT_THROW(map.integrate(v.frame, room.camera, room.pose(0), v.mask), InputError);  // CV_8U, not a weight
  RgbdFrame no_color = v.frame;
  no_color.color = cv::Mat();
  EXPECT_THROW(map.integrate(no_color, room.camera, room.pose(0)), InputError);
  EXPECT_EQ(map.size(), 0u);
  testing::TempDir dir;
  EXPECT_THROW(map.exportMesh(dir.str() + "/empty.ply"), InputError);

  FusionConfig bad;
  bad.integration_stride = 0;
  EXPECT_THROW(StaticMap{bad}, InputError);
  const nlohmann::json j = FusionConfig{};
  EXPECT_EQ(j.get<FusionConfig>().max_surfels, FusionConfig{}.max_surfels);
  FusionConfig negative_budget = FusionConfig{};
  negative_budget.max_surfels = -5;
  EXPECT_THROW(StaticMap{negative_budget}, InputError);
}
}  // namespace
}  // namespace ff
