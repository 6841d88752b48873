#include <gtest/gtest.h>

#include <fstream>

#include "flowfusion/core/camera.h"
#include "flowfusion/core/config.h"
#include "flowfusion/core/error.h"
#include "testing/test_util.h"

namespace ff {
namespace {

TEST(Camera, ProjectBackprojectRoundTrip) {
  const CameraIntrinsics c = *freiburgPreset(1);
  const Eigen::Vector3d p = c.backproject(100.5, 200.25, 2.0);
  const Eigen::Vector2d uv = c.project(p);
  EXPECT_NEAR(uv.x(), 100.5, 1e-12);
  EXPECT_NEAR(uv.y(), 200.25, 1e-12);
}

TEST(Camera, ParseSpecs) {
  EXPECT_DOUBLE_EQ(parseCamera("fr3").fx, 535.4);
  const CameraIntrinsics c = parseCamera("500,501,320,240");
  EXPECT_DOUBLE_EQ(c.fy, 501);
  EXPECT_EQ(c.width, 640);
  EXPECT_THROW(parseCamera("fr4"), InputError);
  EXPECT_THROW(parseCamera("1,2,3"), InputError);
  EXPECT_THROW(parseCamera("a,b,c,d"), InputError);
  EXPECT_THROW(parseCamera("-1,2,3,4"), InputError);
}

TEST(Camera, PyramidLevelKeepsRaysThroughBlockCentres) {
  const CameraIntrinsics c = *freiburgPreset(1);
  const CameraIntrinsics c1 = c.atLevel(1);
  // Level-1 pixel (10, 20) averages level-0 pixels 20..21 x 40..41: its centre is (20.5, 40.5).
  const Eigen::Vector3d r0 = c.backproject(20.5, 40.5, 1.0);
  const Eigen::Vector3d r1 = c1.backproject(10, 20, 1.0);
  EXPECT_NEAR((r0 - r1).norm(), 0, 1e-12);
}

TEST(Config, MergeChecksKeysAndTypes) {
  nlohmann::json base = {{"a", {{"n", 3}, {"x", 1.5}, {"s", "dis"}}}};
  mergeConfig(base, {{"a", {{"x", 2}}}}, "test");
  EXPECT_DOUBLE_EQ(base["a"]["x"].get<double>(), 2.0);
  EXPECT_THROW(mergeConfig(base, {{"a", {{"nope", 1}}}}, "test"), InputError);
  EXPECT_THROW(mergeConfig(base, {{"a", {{"s", 1}}}}, "test"), InputError);
  EXPECT_THROW(mergeConfig(base, {{"a", {{"n", 1.5}}}}, "test"), InputError);
  applyOverride(base, "a.s=farneback");
  EXPECT_EQ(base["a"]["s"], "farneback");
  applyOverride(base, "a.n=7");
  EXPECT_EQ(base["a"]["n"], 7);
  EXPECT_THROW(applyOverride(base, "a.q=1"), InputError);
  EXPECT_THROW(applyOverride(base, "novalue"), InputError);
}

TEST(Camera, ValuesOutOfRangeAreRefusedByName) {
  const auto messageOf = [](const std::string& spec) {
    try {
      parseCameraModel(spec);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(messageOf("500,500,1e300,240").find("principal point"), std::string::npos);
  EXPECT_NE(messageOf("1e-300,500,320,240").find("focal lengths"), std::string::npos);
  EXPECT_NE(messageOf("500,500,320,240,1e300,480").find("image size"), std::string::npos);
  EXPECT_NE(messageOf("500,500,320,240,640.5,480").find("image size"), std::string::npos);
  EXPECT_NE(messageOf("500,500,320,240,640,480,1e9,0,0,0,0").find("distortion"), std::string::npos);
  EXPECT_EQ(messageOf("50,50,31.5,23.5,64,48"), "accepted");
  EXPECT_EQ(messageOf("fr1"), "accepted");
}

struct WrapConfig {
  int count = 3;
  uint64_t seed = 1;
  float gain = 0.5f;
  struct Inner {
    int levels = 4;
  } inner;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(WrapConfig::Inner, levels)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(WrapConfig, count, seed, gain, inner)

std::string resolveError(const std::vector<std::string>& overrides, const std::string& file = "") {
  try {
    resolveConfig(WrapConfig{}, file, overrides);
  } catch (const InputError& e) {
    return e.what();
  }
  return "accepted";
}

TEST(Config, IntegersDoNotWrapAround) {
  EXPECT_EQ(resolveConfig(WrapConfig{}, "", {"inner.levels=6", "gain=0.1"}).inner.levels, 6);
  EXPECT_EQ(resolveConfig(WrapConfig{}, "", {"seed=18446744073709551615"}).seed, 18446744073709551615ull);
  const std::string wrapped = resolveError({"inner.levels=4294967300"});
  EXPECT_NE(wrapped.find("'inner.levels'"), std::string::npos) << wrapped;
  EXPECT_NE(wrapped.find("out of range"), std::string::npos) << wrapped;
  EXPECT_NE(resolveError({"count=2147483648"}).find("'count'"), std::string::npos);
  EXPECT_NE(resolveError({"count=-2147483649"}).find("'count'"), std::string::npos);
  EXPECT_NE(resolveError({"seed=-1"}).find("'seed'"), std::string::npos);
  EXPECT_NE(resolveError({"gain=1e300"}).find("'gain'"), std::string::npos);
  EXPECT_EQ(resolveError({"count=-5", "gain=-1e30"}), "accepted");  // in range; the stage checks its rules
}

TEST(Config, FolderOrGarbageAsConfigFileIsNamed) {
  testing::TempDir tmp;
  const std::string folder = resolveError({}, tmp.str());
  EXPECT_NE(folder.find(tmp.str() + ": is a folder"), std::string::npos) << folder;
  const std::string long_key = "x" + std::string(10000, 'y') + "=1";
  const std::string msg = resolveError({long_key});
  EXPECT_LT(msg.size(), 300u) << msg;
  EXPECT_NE(msg.find("(10003 characters)"), std::string::npos) << msg;
}

}  // namespace
}  // namespace ff
