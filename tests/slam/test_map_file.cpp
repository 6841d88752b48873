// The saved map (map.ffmap): a map of known surfels and keyframes written and read back holds
// exactly what was written; a damaged, truncated, foreign or other-version file, and a map of
// another camera, are refused with a message naming the file and the reason.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/core.hpp>

#include "flowfusion/core/error.h"
#include "flowfusion/slam/map_file.h"
#include "testing/test_util.h"

namespace ff {
namespace {

using testing::inputErrorOf;
using testing::kDeg;
using testing::motion;
using testing::TempDir;

CameraIntrinsics camera() { return {200.0, 201.0, 79.5, 59.25, 160, 120}; }

// Images of seeded random content at the sizes of camera() at level 1 and 80 px wide ferns.
std::shared_ptr<const KeyframeImages> images(int seed) {
  cv::RNG rng(seed);
  auto k = std::make_shared<KeyframeImages>();
  k->camera = camera().atLevel(1);
  const cv::Size size(k->camera.width, k->camera.height), small(80, 60);
  k->intensity.create(size, CV_8U);
  k->depth.create(size, CV_16U);
  k->static_weight.create(size, CV_8U);
  k->small_bgr.create(small, CV_8UC3);
  k->small_depth.create(small, CV_32F);
  rng.fill(k->intensity, cv::RNG::UNIFORM, 0, 256);
  rng.fill(k->depth, cv::RNG::UNIFORM, 0, 65536);
  rng.fill(k->static_weight, cv::RNG::UNIFORM, 0, 256);
  rng.fill(k->small_bgr, cv::RNG::UNIFORM, 0, 256);
  rng.fill(k->small_depth, cv::RNG::UNIFORM, 0.0, 6.0);
  return k;
}

SavedMap knownMap() {
  SavedMap m;
  m.camera = camera();
  m.keyframe_level = 1;
  m.fern_image_width = 80;
  for (int i = 0; i < 50; ++i) {
    Surfel s;
    s.position = Eigen::Vector3f(0.1f * i, -0.03f * i, 1.0f + 1e-7f * i);
    s.normal = Eigen::Vector3f(0.0f, std::sin(0.01f * i), -std::cos(0.01f * i));
    s.radius = 0.004f + 1e-5f * i;
    s.confidence = 2.0f + 0.37f * i;
    s.bgr[0] = 10.5f + i;
    s.bgr[1] = 200.25f - i;
    s.bgr[2] = 0.125f * i;
    s.intensity = 0.01f * i;
    m.surfels.push_back(s);
  }
  for (int k = 0; k < 3; ++k)
    m.keyframes.push_back({motion({0.2 * k, -0.1, 0.05 * k}, {0.0, 0.0, 20.0 * k * kDeg}), images(k + 1)});
  return m;
}

bool sameImage(const cv::Mat& a, const cv::Mat& b) {
  return a.type() == b.type() && a.size() == b.size() && std::equal(a.datastart, a.dataend, b.datastart);
}

std::string bytesOf(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void writeBytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

TEST(MapFile, ReadsBackExactlyWhatWasWritten) {
  const TempDir dir;
  const SavedMap written = knownMap();
  const std::string path = (dir.path() / kMapFileName).string();
  writeMapFile(path, written);
  EXPECT_EQ(mapFileIn(dir.str()), path);  // a run folder names its map file
  const SavedMap read = readMapFile(path);
  EXPECT_EQ(read.path, path);
  EXPECT_EQ(read.camera.fx, written.camera.fx);
  EXPECT_EQ(read.camera.cy, written.camera.cy);
  EXPECT_EQ(read.camera.width, written.camera.width);
  EXPECT_EQ(read.keyframe_level, 1);
  EXPECT_EQ(read.fern_image_width, 80);
  ASSERT_EQ(read.surfels.size(), written.surfels.size());
  for (size_t i = 0; i < read.surfels.size(); ++i) {
    const Surfel &a = read.surfels[i], &b = written.surfels[i];
    EXPECT_EQ(a.position, b.position);
    EXPECT_EQ(a.normal, b.normal);
    EXPECT_EQ(a.radius, b.radius);
    EXPECT_EQ(a.confidence, b.confidence);
    EXPECT_TRUE(std::equal(a.bgr, a.bgr + 3, b.bgr));
    EXPECT_EQ(a.intensity, b.intensity);
  }
  ASSERT_EQ(read.keyframes.size(), written.keyframes.size());
  for (size_t k = 0; k < read.keyframes.size(); ++k) {
    const SavedKeyframe &a = read.keyframes[k], &b = written.keyframes[k];
    EXPECT_TRUE(a.T_world_kf.isApprox(b.T_world_kf, 0)) << "keyframe " << k;
    EXPECT_EQ(a.images->camera.width, b.images->camera.width);
    EXPECT_EQ(a.images->camera.fx, b.images->camera.fx);
    EXPECT_TRUE(sameImage(a.images->intensity, b.images->intensity));
    EXPECT_TRUE(sameImage(a.images->depth, b.images->depth));
    EXPECT_TRUE(sameImage(a.images->static_weight, b.images->static_weight));
    EXPECT_TRUE(sameImage(a.images->small_bgr, b.images->small_bgr));
    EXPECT_TRUE(sameImage(a.images->small_depth, b.images->small_depth));
  }
}

TEST(MapFile, RefusesDamagedTruncatedForeignAndOtherVersionFiles) {
  const TempDir dir;
  const std::string path = (dir.path() / kMapFileName).string();
  writeMapFile(path, knownMap());
  const std::string good = bytesOf(path);
  const auto refusal = [&](const std::string& bytes) {
    writeBytes(path, bytes);
    return inputErrorOf([&] { readMapFile(path); });
  };
  std::string flipped = good;
  flipped[good.size() / 2] ^= 0x10;
  EXPECT_NE(refusal(flipped).find("corrupt or truncated map file (checksum mismatch)"), std::string::npos)
      << refusal(flipped);
  EXPECT_NE(refusal(good.substr(0, good.size() - 1000)).find("checksum"), std::string::npos);
  EXPECT_NE(refusal(good.substr(0, 10)).find("not a flowfusion map file"), std::string::npos);
  EXPECT_NE(refusal("ply\nformat binary_little_endian 1.0\n").find("not a flowfusion map file"), std::string::npos);
  std::string version = good;
  version[8] = 9;
  const std::string v = refusal(version);
  EXPECT_NE(v.find("map file version 9, this build reads version 1"), std::string::npos) << v;
  EXPECT_NE(v.find(path), std::string::npos) << "names the file: " << v;
  const std::string missing = inputErrorOf([&] { readMapFile((dir.path() / "none.ffmap").string()); });
  EXPECT_NE(missing.find("none.ffmap: no map file there"), std::string::npos) << missing;
}

TEST(MapFile, RefusesAMapOfAnotherCameraOrOtherKeyframeImages) {
  SavedMap map = knownMap();
  map.path = "RUN1/map.ffmap";
  SlamConfig slam;
  EXPECT_EQ(inputErrorOf([&] { checkMapFits(map, camera(), slam); }), "no InputError");
  CameraIntrinsics other = camera();
  other.fx = 190.0;
  const std::string intrinsics = inputErrorOf([&] { checkMapFits(map, other, slam); });
  EXPECT_NE(intrinsics.find("RUN1/map.ffmap: the map is of another camera"), std::string::npos) << intrinsics;
  other = camera();
  other.width = 320;
  other.height = 240;
  EXPECT_NE(inputErrorOf([&] { checkMapFits(map, other, slam); }).find("another camera: 160x120"), std::string::npos);
  slam.keyframe_level = 0;
  EXPECT_NE(inputErrorOf([&] { checkMapFits(map, camera(), slam); }).find("slam.keyframe_level 1"), std::string::npos);
  slam = {};
  map.keyframes.clear();
  EXPECT_NE(inputErrorOf([&] { checkMapFits(map, camera(), slam); }).find("no keyframes"), std::string::npos);
}

}  // namespace
}  // namespace ff
