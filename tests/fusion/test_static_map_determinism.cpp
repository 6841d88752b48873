// The map is the same bit for bit whatever the number of threads and their scheduling: every
// parallel reduction in fusion combines its parts in a fixed order or in integers.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cstring>

#include "flowfusion/fusion/static_map.h"
#include "room_fixture.h"

namespace ff {
namespace {

bool bitIdentical(const cv::Mat& a, const cv::Mat& b) {
  if (a.size() != b.size() || a.type() != b.type() || !a.isContinuous() || !b.isContinuous()) return false;
  return std::memcmp(a.data, b.data, a.total() * a.elemSize()) == 0;
}

struct Rendered {
  cv::Mat depth, predicted, stable;
  size_t points = 0;
};

// Fuses a room with a moving sphere (no masks: free-space removal runs too) with at most
// `threads` threads, then renders at the last pose.
Rendered fuseAndRender(int threads) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<size_t>(threads));
  testing::RoomFixture room;
  room.with_sphere = true;
  room.frames = 10;
  StaticMap map{FusionConfig{}};
  for (int i = 0; i < room.frames; ++i) {
    const auto v = room.render(i);
    map.integrate(v.frame, room.camera, room.pose(i), cv::Mat());
  }
  const SE3 pose = room.pose(room.frames - 1);
  Rendered r;
  r.depth = map.predictDepth(pose, room.camera);
  r.predicted = map.predict(pose, room.camera).depth;
  r.stable = map.predictStableDepth(pose, room.camera);
  r.points = map.points().positions.size();
  return r;
}

TEST(StaticMapDeterminism, PredictionsAreBitIdenticalWithOneTwoAndFourThreads) {
  const Rendered one = fuseAndRender(1);
  ASSERT_GT(cv::countNonZero(one.depth), 1000);
  for (int threads : {2, 4, 2}) {
    const Rendered many = fuseAndRender(threads);
    EXPECT_EQ(many.points, one.points) << threads << " threads";
    EXPECT_TRUE(bitIdentical(many.depth, one.depth)) << "predictDepth, " << threads << " threads";
    EXPECT_TRUE(bitIdentical(many.predicted, one.predicted)) << "predict, " << threads << " threads";
    EXPECT_TRUE(bitIdentical(many.stable, one.stable)) << "predictStableDepth, " << threads << " threads";
  }
}

}  // namespace
}  // namespace ff
