#include <gtest/gtest.h>

#include <cmath>

#include "flowfusion/core/error.h"
#include "flowfusion/segmentation/dynamic_score.h"
#include "flowfusion/segmentation/motion_memory.h"

namespace ff {
namespace {

constexpr double kFrameS = 1.0 / 30;  // 30 Hz, as TUM

// A 16x8 frame of a still camera: the left half is the mapped wall 4 m away (cluster 0), the right
// half (from column `first_person_column`) a person 2 m in front of it (cluster 1), the map's wall
// behind the person.
struct PersonInFrontOfTheMap {
  int first_person_column = 8;
  CameraIntrinsics camera{10, 10, 7.5, 3.5, 16, 8};
  ClusterGraph graph;
  cv::Mat depth;
  ResidualImages res;
  cv::Mat previous_b;  // the previous frame's scores per pixel (a still camera carries them as they are)

  explicit PersonInFrontOfTheMap(int first_person_column_ = 8) : first_person_column(first_person_column_) {
    const int p = first_person_column;
    graph.labels.create(8, 16, CV_32S);
    depth.create(8, 16, CV_32F);
    for (int v = 0; v < 8; ++v)
      for (int u = 0; u < 16; ++u) {
        graph.labels.at<int>(v, u) = u < p ? 0 : 1;
        depth.at<float>(v, u) = u < p ? 4.f : 2.f;
      }
    graph.num_clusters = 2;
    graph.sizes = {8 * p, 8 * (16 - p)};
    graph.mean_depth = {4.f, 2.f};
    graph.centroids.resize(2);
    graph.edges = {{0, 1}};
    res.r_M.create(8, 16, CV_32F);
    res.r_M.colRange(0, p).setTo(0.f);
    res.r_M.colRange(p, 16).setTo(2.f);  // metres in front of the map
    res.r_F.create(8, 16, CV_32F);
  }

  // One frame: the person's flow residual (pixels), scores with the prior and the memory, the
  // memory updated.
  DynamicScores frame(MotionMemory& memory, const ScoreConfig& config, int index, float person_flow_px) {
    res.r_F.setTo(0.f);
    res.r_F.colRange(first_person_column, 16).setTo(person_flow_px);
    res.prior = previous_b;
    const double t = index * kFrameS;
    res.memory = memory.recall(SE3::Identity(), t);
    DynamicScores s = computeDynamicScores(graph, res, config);
    memory.remember(graph, s, depth, SE3::Identity(), t);
    previous_b = pixelScores(graph, s);
    return s;
  }
};

TEST(MotionMemory, APersonWhoStopsInFrontOfTheMapStaysDynamicForTheHoldTime) {
  PersonInFrontOfTheMap scene;
  ScoreConfig config;
  config.model_memory_s = 2.0 + 0.5 * kFrameS;  // 2 s, away from a frame boundary
  const float walking_px = 10.f;  // delta 0.22 > model_motion_delta
  MotionMemory memory(config.model_memory_s, scene.camera);
  MotionMemory none(0.0, scene.camera);
  PersonInFrontOfTheMap twin;  // the same frames without the memory
  for (int f = 0; f < 10; ++f) {  // walks
    const DynamicScores s = scene.frame(memory, config, f, walking_px);
    EXPECT_GT(s.b[1], 0.5f) << f;
    EXPECT_EQ(s.moving[1], f > 0) << f;  // remembered from its second moving frame
    EXPECT_GT(twin.frame(none, config, f, walking_px).b[1], 0.5f) << f;
  }
  // Stops, sits for 1.5 s: no motion evidence; the memory keeps the map's occlusion term.
  for (int f = 10; f < 55; ++f) {
    const DynamicScores s = scene.frame(memory, config, f, 0.f);
    EXPECT_GT(s.b[1], 0.5f) << "frame " << f;
    EXPECT_FALSE(s.moving[1]);  // the memory is not motion: it does not renew itself
    EXPECT_LT(s.b[0], 0.5f);
    EXPECT_LT(twin.frame(none, config, f, 0.f).b[1], 0.5f) << "without the memory, frame " << f;
  }
  // Still 2 s after the last step: released.
  int released = -1;
  for (int f = 55; f < 80 && released < 0; ++f)
    if (scene.frame(memory, config, f, 0.f).b[1] < 0.5f) released = f;
  EXPECT_EQ(released, 9 + 61);  // the last moving frame + 2 s at 30 Hz (60 frames) + 1
  // Moving again (two frames: the first one only scores) renews it.
  EXPECT_GT(scene.frame(memory, config, 80, walking_px).b[1], 0.5f);
  EXPECT_GT(scene.frame(memory, config, 81, walking_px).b[1], 0.5f);
  EXPECT_GT(scene.frame(memory, config, 82, 0.f).b[1], 0.5f);
}

TEST(MotionMemory, AStaticSurfaceFlaggedOnceIsNotRememberedTwiceIsReleasedAfterTheHoldTime) {
  // A thin static structure the map never fused, with flow noise above model_motion_delta.
  ScoreConfig config;
  config.model_memory_s = 0.5 + 0.5 * kFrameS;
  for (const int noisy_frames : {1, 2}) {
    PersonInFrontOfTheMap scene;
    MotionMemory memory(config.model_memory_s, scene.camera);
    for (int f = 0; f < noisy_frames; ++f) EXPECT_GT(scene.frame(memory, config, f, 10.f).b[1], 0.5f);
    int dynamic_frames = 0;
    for (int f = noisy_frames; f < 60; ++f) dynamic_frames += scene.frame(memory, config, f, 0.f).b[1] > 0.5f;
    // One frame: static at once. Two: remembered from the second, 0.5 s at 30 Hz, then static.
    EXPECT_EQ(dynamic_frames, noisy_frames == 1 ? 0 : 15) << noisy_frames;
    EXPECT_LT(scene.frame(memory, config, 60, 0.f).b[1], 0.5f);
  }
}

TEST(MotionMemory, ARegionCoveringMostOfTheImageIsNotRemembered) {
  // Three quarters of the image "moving": the background under a wrong pose, not a person.
  PersonInFrontOfTheMap scene(4);
  ScoreConfig config;
  MotionMemory memory(config.model_memory_s, scene.camera);
  for (int f = 0; f < 5; ++f) {
    const DynamicScores s = scene.frame(memory, config, f, 10.f);
    EXPECT_GT(s.b[1], 0.5f);
    EXPECT_FALSE(s.moving[1]);
  }
  EXPECT_LT(scene.frame(memory, config, 5, 0.f).b[1], 0.5f);  // static as soon as it stops
}

TEST(MotionMemory, IsCarriedAlongTheCameraMotionInThreeD) {
  PersonInFrontOfTheMap scene;
  ScoreConfig config;
  config.model_memory_s = 1.0;
  MotionMemory memory(config.model_memory_s, scene.camera);
  EXPECT_FALSE(scene.frame(memory, config, 0, 10.f).moving[1]);
  EXPECT_TRUE(scene.frame(memory, config, 1, 10.f).moving[1]);
  // The camera moves 0.7 m to the right: the person (2 m, columns 8-15) shifts 3.5 pixels to the
  // left and splats onto columns 4-12, the wall (4 m) 1.75 pixels onto columns 0-6; the nearer
  // surface wins where both land.
  SE3 T_world_cam = SE3::Identity();
  T_world_cam.translation() = Eigen::Vector3d(0.7, 0, 0);
  const cv::Mat recent = memory.recall(T_world_cam, 0.1);
  ASSERT_EQ(recent.size(), scene.depth.size());
  for (int v = 0; v < 8; ++v) {
    for (int u = 4; u <= 12; ++u) EXPECT_EQ(recent.at<float>(v, u), 1.f) << u << "," << v;
    for (int u = 0; u < 4; ++u) EXPECT_TRUE(std::isnan(recent.at<float>(v, u))) << u << "," << v;  // wall
    for (int u = 13; u < 16; ++u) EXPECT_TRUE(std::isnan(recent.at<float>(v, u))) << u << "," << v;  // nothing
  }
  // Older than the hold time: remembered as not recent.
  const cv::Mat old = memory.recall(T_world_cam, 1.5);
  EXPECT_EQ(old.at<float>(4, 6), 0.f);
  // Frames without a remember() in between: carried from the last remembered frame.
  EXPECT_EQ(memory.recall(SE3::Identity(), 0.5).at<float>(4, 10), 1.f);
}

TEST(MotionMemory, OffOrBadSettingsAndInput) {
  PersonInFrontOfTheMap scene;
  MotionMemory off(0.0, scene.camera);
  ScoreConfig config;
  scene.frame(off, config, 0, 10.f);
  EXPECT_TRUE(off.recall(SE3::Identity(), 0.1).empty());
  EXPECT_THROW(MotionMemory(-1.0, scene.camera), InputError);
  config.model_memory_s = -0.5;
  EXPECT_THROW(validate(config), InputError);
  config.model_memory_s = std::nan("");
  EXPECT_THROW(validate(config), InputError);
  MotionMemory memory(1.0, scene.camera);
  const DynamicScores s = computeDynamicScores(scene.graph, scene.res, ScoreConfig{});
  EXPECT_THROW(memory.remember(scene.graph, s, cv::Mat(4, 4, CV_32F, cv::Scalar(1.f)), SE3::Identity(), 0), InputError);
  scene.res.memory = cv::Mat(4, 4, CV_32F, cv::Scalar(1.f));
  EXPECT_THROW(computeDynamicScores(scene.graph, scene.res, ScoreConfig{}), InputError);
}

}  // namespace
}  // namespace ff
