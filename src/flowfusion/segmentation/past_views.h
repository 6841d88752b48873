#pragma once
// What earlier views saw where a point of the current frame lies: a few past scored frames (depth,
// dynamic mask, pose) at the scores' resolution. A surface that comes back into view, or that
// parallax uncovers beside a mover, can lie in front of map surfels fused from other viewpoints;
// the map's occlusion term then takes it for a mover, and the motion memory and the carried score
// hold it (the role swap of issue 29). If an earlier view saw a static surface at that very point
// and none saw through it, it has stood there all along: the map's occlusion there is no evidence
// of motion (ScoreConfig::model_views, docs/tuning.md#model_views).
#include <deque>
#include <opencv2/core.hpp>

#include "flowfusion/core/camera.h"
#include "flowfusion/core/se3.h"

namespace ff {

// Per pixel of the current frame, what the kept views saw at its point.
enum class PastSight : uint8_t {
  kNothing = 0,      // no kept view saw the point (out of view, hidden, no depth, or a mover there)
  kStaticThere = 1,  // a view saw a static surface at it (within the margin), none saw through it
  kSeenThrough = 2,  // a view saw a static surface beyond it: the point was empty then
};

class PastViews {
 public:
  // camera: the frames' camera at the resolution of the scores. Keeps one frame of every
  // `every_frames` (>= 1), the latest `views` of them (0 = none: sight() sees nothing).
  PastViews(const CameraIntrinsics& camera, int every_frames, int views);

  // A scored frame at `timestamp` (s): depth (CV_32F metres, the camera's size), scores (CV_32F,
  // b per pixel; above kDynamicScore is a mover; empty = all static) and its pose.
  void add(const cv::Mat& depth, const cv::Mat& scores, const SE3& T_world_cam, double timestamp);
  bool empty() const { return views_.empty(); }

  // PastSight per pixel (CV_8U) of a frame's depth seen from T_world_cam at `timestamp`, tested
  // where `where` is non-zero (CV_8U of the depth's size), kNothing elsewhere, by the views at
  // least min_age_s older. A view compares the smallest depth over the 3x3 pixels the point
  // projects to with the point's depth there: within margin * depth static there, beyond it seen
  // through (a mover among those pixels: nothing).
  cv::Mat sight(const cv::Mat& depth, const SE3& T_world_cam, double timestamp, double min_age_s, double margin,
                const cv::Mat& where) const;

  // r_M (modelOcclusion's, CV_32F) with 0 where `sight` (sight()'s, of r_M's size) is kStaticThere.
  static cv::Mat withoutStaticThere(const cv::Mat& r_M, const cv::Mat& sight);

 private:
  struct View {
    cv::Mat depth;
    cv::Mat dynamic;  // CV_8U, non-zero on the frame's movers
    SE3 T_cam_world;
    double timestamp;
  };
  PastSight sightOf(const Eigen::Vector3d& X_world, double newest_s, double margin) const;

  CameraIntrinsics camera_;
  int every_frames_, views_kept_;
  int added_ = 0;
  std::deque<View> views_;
};

}  // namespace ff
