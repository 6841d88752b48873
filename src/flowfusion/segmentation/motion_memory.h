#pragma once
// The memory of where objects moved: for each pixel of the last scored frame, how many seconds ago
// its surface last belonged to a moving group of clusters, carried in 3D into a later frame along
// the camera's motion. A person who stops, stands or sits in front of the mapped background has no
// motion evidence left, and without it model_needs_motion drops the map's occlusion term and the
// person is fused; while the memory is younger than ScoreConfig::model_memory_s it counts as that
// evidence (residuals.memory). What counts as moving is DynamicScores::moving (motion in two frames
// in a row); the memory ages whenever nothing moves there, so a static surface flagged for a while
// is released after model_memory_s.
#include <opencv2/core.hpp>

#include "flowfusion/core/camera.h"
#include "flowfusion/core/se3.h"
#include "flowfusion/segmentation/dynamic_score.h"

namespace ff {

class MotionMemory {
 public:
  // hold_s: how long (seconds) a moved region stays remembered; 0 = never (recall gives nothing).
  // camera: the frames' camera at the resolution of the scores.
  MotionMemory(double hold_s, const CameraIntrinsics& camera);

  // For the frame at `timestamp` (seconds) seen from T_world_cam: 1 where the carried memory is at
  // most hold_s old, 0 where older, NaN where nothing was carried (CV_32F, the camera's size);
  // empty before the first remember() or when off. Keeps the carried ages for the remember() of
  // the same frame.
  cv::Mat recall(const SE3& T_world_cam, double timestamp);

  // After the frame's scores: pixels of moving clusters (scores.moving) are remembered as moving
  // now, the others keep the age recall() carried to them. depth: the frame's depth (CV_32F
  // metres, the camera's size) that carries the memory into later frames.
  void remember(const ClusterGraph& graph, const DynamicScores& scores, const cv::Mat& depth, const SE3& T_world_cam,
                double timestamp);

 private:
  double hold_s_;
  CameraIntrinsics camera_;
  cv::Mat age_s_;  // per pixel of the remembered frame, seconds; NaN = no memory
  cv::Mat depth_;  // that frame's depth, metres
  SE3 T_world_cam_ = SE3::Identity();
  double timestamp_ = 0;
  cv::Mat carried_s_;  // ages carried into the frame of the last recall()
  double carried_timestamp_ = 0;
};

}  // namespace ff
