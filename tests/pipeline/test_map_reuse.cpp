// Map reuse (`run --map-in`) in the system: a first run turns on the spot in a synthetic room from
// the true first pose and leaves its map file; a second run, started at a wrong pose (identity),
// from another place and turning the other way, finds itself among the keyframes at its first
// frame and then tracks in the first run's world frame: its poses are on the truth with no
// alignment, and it extends the map; its keyframes, all in views the first run's keyframes cover,
// keep only their pose-graph nodes (slam.cull_covered_keyframes). A run in another room is never
// localized and says so, with no poses and nothing fused.
#include <gtest/gtest.h>

#include <cstdio>
#include <memory>

#include "flowfusion/pipeline/flowfusion_system.h"
#include "flowfusion/synth/synthetic_scene.h"
#include "testing/test_util.h"

namespace ff {
namespace {

using testing::kDeg;

constexpr int kFirstFrames = 60;  // 3 degrees a frame: half a turn
constexpr int kSecondFrames = 30;

// The camera of `scene`'s first frame, turned by `deg` about the world's z axis and moved by `t_m`.
SE3 turned(const synth::SyntheticScene& scene, double deg, const Eigen::Vector3d& t_m = Eigen::Vector3d::Zero()) {
  SE3 T = scene.cameraPose(0);
  T.linear() = Eigen::AngleAxisd(deg * kDeg, Eigen::Vector3d::UnitZ()).toRotationMatrix() * T.linear();
  T.translation() += t_m;
  return T;
}

std::unique_ptr<synth::SyntheticScene> room(uint64_t seed) {
  synth::SynthConfig c;
  c.seed = seed;
  c.objects = 0;
  c.width = 320;
  c.height = 240;
  c.frames = kFirstFrames;
  return std::make_unique<synth::SyntheticScene>(c);
}

SystemConfig config() {
  SystemConfig c;
  c.pipeline.segmentation = false;  // a static room: the odometry and the map are enough
  c.odometry.finest_level = 0;
  c.slam.keyframe_level = 0;
  return c;
}

// The first run's map as the next run reads it, through the file.
SavedMap firstRunMap(const synth::SyntheticScene& scene, const testing::TempDir& dir) {
  FlowFusionSystem system(config(), scene.camera(), turned(scene, 0));
  for (int i = 0; i < kFirstFrames; ++i) system.process(scene.renderAt(turned(scene, 3.0 * i), scene.timestamp(i)).frame);
  system.finishLoopClosure();
  const std::string path = (dir.path() / kMapFileName).string();
  writeMapFile(path, savedMap(system.map(), system.savedKeyframes(), scene.camera(), config().slam));
  return readMapFile(path);
}

TEST(MapReuse, ASecondRunContinuesInTheFirstRunsWorldFrame) {
  if (!loopClosureAvailable()) GTEST_SKIP() << "built without Ceres (libceres-dev): no map reuse";
  const auto scene = room(1);
  const testing::TempDir dir;
  const SavedMap map = firstRunMap(*scene, dir);
  ASSERT_GE(map.keyframes.size(), 5u);
  // From 100 degrees back to 42, 4 cm aside: poses the first run never had.
  const Eigen::Vector3d aside(0.03, -0.025, 0.01);
  FlowFusionSystem system(config(), scene->camera(), SE3::Identity(), &map);
  double worst = 0;
  for (int i = 0; i < kSecondFrames; ++i) {
    const SE3 truth = turned(*scene, 100.0 - 2.0 * i, aside);
    const FrameResult r = system.process(scene->renderAt(truth, scene->timestamp(kFirstFrames + i)).frame);
    EXPECT_TRUE(r.tracking_ok) << "frame " << i << ": " << r.message;
    worst = std::max(worst, translationNorm(r.T_world_cam.inverse() * truth));
  }
  system.finishLoopClosure();
  const MapReuse& reuse = *system.mapReuse();
  std::printf("[ measured ] localized at frame %d; largest error without alignment %.4f m; keyframes %zu -> %d, "
              "surfels %zu -> %zu\n", reuse.localized_at_frame, worst, map.keyframes.size(), system.slamKeyframes(),
              map.surfels.size(), system.map()->size());
  EXPECT_EQ(reuse.localized_at_frame, 0);
  EXPECT_EQ(reuse.unlocalized_frames, 0);
  EXPECT_LT(worst, 0.02);
  EXPECT_EQ(system.trajectory().size(), static_cast<size_t>(kSecondFrames));
  EXPECT_EQ(system.slamKeyframes(), static_cast<int>(map.keyframes.size()));  // covered: none added
  EXPECT_GT(system.map()->size(), map.surfels.size());
}

TEST(MapReuse, ARunInAnotherRoomIsNeverLocalizedAndSaysSo) {
  if (!loopClosureAvailable()) GTEST_SKIP() << "built without Ceres (libceres-dev): no map reuse";
  const auto scene = room(1), other = room(2);
  const testing::TempDir dir;
  const SavedMap map = firstRunMap(*scene, dir);
  FlowFusionSystem system(config(), other->camera(), SE3::Identity(), &map);
  for (int i = 0; i < 5; ++i) {
    const FrameResult r = system.process(other->render(i).frame);
    EXPECT_FALSE(r.tracking_ok);
    EXPECT_FALSE(r.has_pose);
    EXPECT_EQ(r.message, "not localized in the saved map yet: no keyframe matches");
  }
  EXPECT_EQ(system.mapReuse()->localized_at_frame, -1);
  EXPECT_EQ(system.mapReuse()->unlocalized_frames, 5);
  EXPECT_TRUE(system.trajectory().empty());
  EXPECT_EQ(system.map()->size(), map.surfels.size());  // nothing fused
}

TEST(MapReuse, RefusesAMapWithoutLoopClosure) {
  const auto scene = room(1);
  SavedMap map;
  map.path = "RUN1/map.ffmap";
  map.camera = scene->camera();
  SystemConfig c = config();
  c.slam.loop_closure = LoopClosureMode::Off;
  const std::string message = testing::inputErrorOf([&] { FlowFusionSystem system(c, scene->camera(), SE3::Identity(), &map); });
  EXPECT_NE(message.find("RUN1/map.ffmap: continuing in a saved map needs loop closure"), std::string::npos) << message;
}

}  // namespace
}  // namespace ff
