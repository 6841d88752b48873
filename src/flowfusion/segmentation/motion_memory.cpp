#include "flowfusion/segmentation/motion_memory.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "flowfusion/core/error.h"
#include "flowfusion/segmentation/score_carry.h"

namespace ff {

MotionMemory::MotionMemory(double hold_s, const CameraIntrinsics& camera) : hold_s_(hold_s), camera_(camera) {
  if (!(hold_s >= 0 && std::isfinite(hold_s)))
    throw InputError("MotionMemory: the hold time must be a finite number of seconds >= 0");
}

cv::Mat MotionMemory::recall(const SE3& T_world_cam, double timestamp) {
  carried_s_.release();
  if (hold_s_ <= 0 || age_s_.empty()) return {};
  const float nan = std::numeric_limits<float>::quiet_NaN();
  carried_s_ = carryScores(age_s_, depth_, camera_, T_world_cam.inverse() * T_world_cam_, nan);
  carried_s_ += std::max(0.0, timestamp - timestamp_);  // NaN stays NaN
  carried_timestamp_ = timestamp;
  cv::Mat recent(carried_s_.size(), CV_32F);
  const float hold = static_cast<float>(hold_s_);
  for (int v = 0; v < recent.rows; ++v) {
    const float* a = carried_s_.ptr<float>(v);
    float* r = recent.ptr<float>(v);
    for (int u = 0; u < recent.cols; ++u) r[u] = std::isnan(a[u]) ? nan : (a[u] <= hold ? 1.f : 0.f);
  }
  return recent;
}

void MotionMemory::remember(const ClusterGraph& graph, const DynamicScores& scores, const cv::Mat& depth,
                            const SE3& T_world_cam, double timestamp) {
  if (hold_s_ <= 0) return;
  const cv::Mat& labels = graph.labels;
  if (depth.type() != CV_32FC1 || depth.size() != labels.size() || depth.cols != camera_.width ||
      depth.rows != camera_.height ||
      static_cast<int>(scores.moving.size()) != graph.num_clusters)
    throw InputError("MotionMemory: depth, labels and scores of one frame must match");
  const bool carried = !carried_s_.empty() && carried_timestamp_ == timestamp;
  age_s_.create(labels.size(), CV_32F);
  for (int v = 0; v < labels.rows; ++v) {
    const int* l = labels.ptr<int>(v);
    const float* c = carried ? carried_s_.ptr<float>(v) : nullptr;
    float* a = age_s_.ptr<float>(v);
    for (int u = 0; u < labels.cols; ++u) {
      const bool moving = l[u] >= 0 && l[u] < graph.num_clusters && scores.moving[l[u]];
      a[u] = moving ? 0.f : (c ? c[u] : std::numeric_limits<float>::quiet_NaN());
    }
  }
  depth_ = depth.clone();
  T_world_cam_ = T_world_cam;
  timestamp_ = timestamp;
  carried_s_.release();
}

}  // namespace ff
