#include <gtest/gtest.h>

#include "flowfusion/core/camera.h"
#include "flowfusion/core/config.h"
#include "flowfusion/core/error.h"

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

}  // namespace
}  // namespace ff
