#include "flowfusion/segmentation/past_views.h"

#include <cmath>
#include <string>

#include "flowfusion/core/error.h"
#include "flowfusion/core/rgbd_frame.h"
#include "flowfusion/segmentation/score_evidence.h"

namespace ff {

namespace {

// Whether a mover is among the 3x3 pixels around (u, v).
bool moverAround(const cv::Mat& dynamic, int u, int v) {
  const cv::Rect around = cv::Rect(u - 1, v - 1, 3, 3) & cv::Rect(0, 0, dynamic.cols, dynamic.rows);
  return cv::countNonZero(dynamic(around)) > 0;
}

}  // namespace

PastViews::PastViews(const CameraIntrinsics& camera, int every_frames, int views)
    : camera_(camera), every_frames_(every_frames), views_kept_(views) {
  if (every_frames < 1 || views < 0)
    throw InputError("PastViews: every_frames (" + std::to_string(every_frames) + ") must be at least 1 and views (" +
                     std::to_string(views) + ") at least 0");
}

void PastViews::add(const cv::Mat& depth, const cv::Mat& scores, const SE3& T_world_cam, double timestamp) {
  if (depth.type() != CV_32FC1 || depth.cols != camera_.width || depth.rows != camera_.height ||
      (!scores.empty() && (scores.type() != CV_32FC1 || scores.size() != depth.size())))
    throw InputError("PastViews: depth and scores must be CV_32FC1 of the camera's size");
  if (views_kept_ == 0 || added_++ % every_frames_ != 0) return;
  View view{depth.clone(), cv::Mat(depth.size(), CV_8U, cv::Scalar(0)), T_world_cam.inverse(), timestamp};
  if (!scores.empty()) view.dynamic = scores > kDynamicScore;
  views_.push_back(std::move(view));
  if (static_cast<int>(views_.size()) > views_kept_) views_.pop_front();
}

PastSight PastViews::sightOf(const Eigen::Vector3d& X_world, double newest_s, double margin) const {
  PastSight seen = PastSight::kNothing;
  for (const View& view : views_) {
    if (view.timestamp > newest_s) break;  // the views are in time order
    const Eigen::Vector3d X = view.T_cam_world * X_world;
    if (X.z() <= 0) continue;
    const Eigen::Vector2d p = camera_.project(X);
    if (!camera_.inImage(p.x(), p.y())) continue;
    const int u = static_cast<int>(std::lround(p.x())), v = static_cast<int>(std::lround(p.y()));
    const float d = smallestDepthAround(view.depth, u, v);
    if (!(d > 0) || moverAround(view.dynamic, u, v)) continue;
    if (d > X.z() * (1 + margin)) return PastSight::kSeenThrough;
    if (d >= X.z() * (1 - margin)) seen = PastSight::kStaticThere;
  }
  return seen;
}

cv::Mat PastViews::sight(const cv::Mat& depth, const SE3& T_world_cam, double timestamp, double min_age_s,
                         double margin, const cv::Mat& where) const {
  if (depth.type() != CV_32FC1 || depth.cols != camera_.width || depth.rows != camera_.height ||
      where.type() != CV_8UC1 || where.size() != depth.size())
    throw InputError("PastViews::sight: depth (CV_32FC1) and where (CV_8UC1) must be of the camera's size");
  cv::Mat out(depth.size(), CV_8U, cv::Scalar(static_cast<uint8_t>(PastSight::kNothing)));
  if (views_.empty()) return out;
  cv::parallel_for_(cv::Range(0, depth.rows), [&](const cv::Range& rows) {
    for (int v = rows.start; v < rows.end; ++v) {
      const float* z = depth.ptr<float>(v);
      const uint8_t* w = where.ptr<uint8_t>(v);
      uint8_t* o = out.ptr<uint8_t>(v);
      for (int u = 0; u < depth.cols; ++u)
        if (w[u] && z[u] > 0)
          o[u] = static_cast<uint8_t>(
              sightOf(T_world_cam * camera_.backproject(u, v, z[u]), timestamp - min_age_s, margin));
    }
  });
  return out;
}

cv::Mat PastViews::withoutStaticThere(const cv::Mat& r_M, const cv::Mat& sight) {
  if (r_M.type() != CV_32FC1 || sight.type() != CV_8UC1 || r_M.size() != sight.size())
    throw InputError("PastViews::withoutStaticThere: r_M (CV_32FC1) and sight (CV_8UC1) must be of one size");
  cv::Mat out = r_M.clone();
  out.setTo(0.f, sight == static_cast<uint8_t>(PastSight::kStaticThere));
  return out;
}

}  // namespace ff
