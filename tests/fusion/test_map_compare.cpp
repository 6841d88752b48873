#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "flowfusion/core/error.h"
#include "flowfusion/fusion/map_compare.h"
#include "flowfusion/fusion/static_map.h"
#include "room_fixture.h"
#include "testing/test_util.h"

namespace ff {
namespace {

// 200 x 200 points, 1 cm apart, on the plane z = 1.
std::vector<Eigen::Vector3f> plane() {
  std::vector<Eigen::Vector3f> points;
  for (int y = 0; y < 200; ++y)
    for (int x = 0; x < 200; ++x) points.emplace_back(0.01f * x, 0.01f * y, 1.0f);
  return points;
}

void expectThrowsNaming(const std::string& path, const std::string& what) {
  try {
    readMapPoints(path);
    ADD_FAILURE() << "no InputError for " << what;
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

TEST(MapCompare, IdenticalMapsDoNotDiffer) {
  const auto points = plane();
  const MapComparison c = compareMaps(points, points, 0.03);
  for (const MapDifference& d : {c.test_to_reference, c.reference_to_test}) {
    EXPECT_EQ(d.points, points.size());
    EXPECT_EQ(d.mean_m, 0.0);
    EXPECT_EQ(d.median_m, 0.0);
    EXPECT_EQ(d.fraction_beyond, 0.0);
  }
}

TEST(MapCompare, MovedPointsCountInTheDirectionThatHasThem) {
  const auto reference = plane();
  auto test = reference;
  // Every 20th point 10 cm off the plane: 5% of TEST lies 10 cm from REFERENCE, while each
  // REFERENCE point under a moved one still has a TEST neighbour 1 cm away on the plane.
  for (size_t k = 0; k < test.size(); k += 20) test[k].z() += 0.1f;
  const MapComparison c = compareMaps(reference, test, 0.03);
  EXPECT_EQ(c.threshold_m, 0.03);
  EXPECT_EQ(c.test_to_reference.points, test.size());
  EXPECT_NEAR(c.test_to_reference.fraction_beyond, 0.05, 1e-9);
  EXPECT_NEAR(c.test_to_reference.mean_m, 0.05 * 0.1, 1e-6);
  EXPECT_EQ(c.test_to_reference.median_m, 0.0);
  EXPECT_EQ(c.reference_to_test.fraction_beyond, 0.0);
  EXPECT_NEAR(c.reference_to_test.mean_m, 0.05 * 0.01, 1e-6);
  EXPECT_EQ(c.reference_to_test.median_m, 0.0);

  // A threshold above the offset counts nothing.
  EXPECT_EQ(mapDifference(test, reference, 0.2).fraction_beyond, 0.0);
}

TEST(MapCompare, MedianOfAnEvenCountAndThresholdIsExclusive) {
  const std::vector<Eigen::Vector3f> from{{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}}, to{{0, 0, 0}};
  const MapDifference d = mapDifference(from, to, 1.0);
  EXPECT_DOUBLE_EQ(d.median_m, 1.5);
  EXPECT_DOUBLE_EQ(d.mean_m, 1.5);
  EXPECT_DOUBLE_EQ(d.fraction_beyond, 0.5);  // 2 and 3 m; 1 m is not beyond 1 m
}

TEST(MapCompare, EmptyMapsAndBadThreshold) {
  const auto points = plane();
  const MapDifference none = mapDifference({}, points, 0.03);
  EXPECT_EQ(none.points, 0u);
  EXPECT_EQ(none.fraction_beyond, 0.0);
  EXPECT_THROW(mapDifference(points, {}, 0.03), InputError);
  EXPECT_THROW(compareMaps(points, points, 0.0), InputError);
  EXPECT_THROW(compareMaps(points, points, -1.0), InputError);
}

// A wall 2 m before an 80x60 camera (1/30 m between pixels there), seen from two poses 10 cm
// apart along the wall (3 pixel columns): the truth holds each wall point once. The voxels are the
// pixels' spacing with the points at their centres, so no rounding decides which voxel is whose.
TEST(MapCompare, TruthCloudHoldsAWallSeenTwiceOnceAndFindsItsDoubledCopy) {
  CameraIntrinsics camera;
  camera.fx = camera.fy = 60;
  camera.cx = 39.5;
  camera.cy = 29.5;
  camera.width = 80;
  camera.height = 60;
  const cv::Mat depth(60, 80, CV_32FC1, cv::Scalar(2.0f));
  const double voxel_m = 1.0 / 30.0;
  SE3 here = SE3::Identity(), aside = SE3::Identity();
  here.translation() = Eigen::Vector3d(0, 0, voxel_m / 2);
  aside.translation() = Eigen::Vector3d(0.1, 0, voxel_m / 2);
  TruthCloud truth(voxel_m);
  truth.addDepth(depth, camera, here, 1);
  truth.addDepth(depth, camera, aside, 1);
  ASSERT_EQ(truth.points().size(), 80u * 60u + 3u * 60u);
  for (const auto& p : truth.points()) ASSERT_NEAR(p.z(), 2.0 + voxel_m / 2, 1e-6);

  // The map fused the wall twice, the second copy 5 cm behind the first: half of it is doubled.
  std::vector<Eigen::Vector3f> doubled = truth.points();
  for (const auto& p : truth.points()) doubled.push_back(p + Eigen::Vector3f(0, 0, 0.05f));
  EXPECT_DOUBLE_EQ(mapDifference(doubled, truth.points(), 0.02).fraction_beyond, 0.5);
  // A wall 1 cm off stays within 2 cm.
  std::vector<Eigen::Vector3f> near_wall;
  for (const auto& p : truth.points()) near_wall.push_back(p + Eigen::Vector3f(0, 0, 0.01f));
  EXPECT_EQ(mapDifference(near_wall, truth.points(), 0.02).fraction_beyond, 0.0);

  TruthCloud every_other(voxel_m);
  every_other.addDepth(depth, camera, here, 2);
  EXPECT_EQ(every_other.points().size(), 40u * 30u);
  EXPECT_THROW(TruthCloud(0.0), InputError);
  EXPECT_THROW(every_other.addDepth(cv::Mat(60, 80, CV_16UC1), camera, here, 1), InputError);
}

TEST(MapCompare, ReadsTheExportedPointCloudBack) {
  testing::RoomFixture room;
  room.frames = 3;
  StaticMap map;
  for (int i = 0; i < room.frames; ++i) map.integrate(room.render(i).frame, room.camera, room.pose(i));
  const std::vector<Eigen::Vector3f> expected = map.points().positions;
  ASSERT_GT(expected.size(), 1000u);

  testing::TempDir dir;
  const std::string path = dir.str() + "/map_points.ply";
  map.exportPointCloud(path);
  const std::vector<Eigen::Vector3f> read = readMapPoints(path);
  ASSERT_EQ(read.size(), expected.size());
  for (size_t k = 0; k < read.size(); ++k) ASSERT_EQ(read[k], expected[k]) << "point " << k;

  // Half a binary PLY: the header promises more vertices than the file holds.
  const std::string truncated = dir.str() + "/truncated.ply";
  std::filesystem::copy_file(path, truncated);
  std::filesystem::resize_file(truncated, std::filesystem::file_size(path) / 2);
  expectThrowsNaming(truncated, "a truncated PLY");
}

TEST(MapCompare, BadFilesThrowInputErrorNamingTheFile) {
  testing::TempDir dir;
  expectThrowsNaming(dir.str() + "/missing.ply", "a missing file");
  expectThrowsNaming(dir.str(), "a folder");

  const std::string garbage = dir.str() + "/garbage.ply";
  std::ofstream(garbage) << "not a ply file\n";
  expectThrowsNaming(garbage, "a file that is not PLY");

  const std::string empty = dir.str() + "/empty.ply";
  std::ofstream(empty) << "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
                          "property float z\nend_header\n";
  expectThrowsNaming(empty, "a PLY without points");

  const std::string nan = dir.str() + "/nan.ply";
  std::ofstream(nan) << "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
                        "property float z\nend_header\n0 0 1\nnan 0 1\n";
  expectThrowsNaming(nan, "a PLY with a NaN coordinate");
}

}  // namespace
}  // namespace ff
