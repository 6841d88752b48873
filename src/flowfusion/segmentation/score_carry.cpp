#include "flowfusion/segmentation/score_carry.h"

#include <limits>

namespace ff {

cv::Mat carryScores(const cv::Mat& prev_scores, const cv::Mat& prev_depth, const CameraIntrinsics& cam,
                    const SE3& T_cur_prev, float fill) {
  cv::Mat out(prev_scores.size(), CV_32F, cv::Scalar(fill));
  cv::Mat zbuf(prev_scores.size(), CV_32F, cv::Scalar(std::numeric_limits<float>::infinity()));
  for (int y = 0; y < prev_depth.rows; ++y)
    for (int x = 0; x < prev_depth.cols; ++x) {
      const float b = prev_scores.at<float>(y, x);
      const float z = prev_depth.at<float>(y, x);
      if (z <= 0) continue;
      const Eigen::Vector3d q = T_cur_prev * cam.backproject(x, y, z);
      if (q.z() <= 0) continue;
      const Eigen::Vector2d uv = cam.project(q);
      // Splat to the 2x2 neighbourhood so that no holes open up.
      for (int dy = 0; dy <= 1; ++dy)
        for (int dx = 0; dx <= 1; ++dx) {
          const int u = static_cast<int>(uv.x()) + dx, v = static_cast<int>(uv.y()) + dy;
          if (u < 0 || v < 0 || u >= out.cols || v >= out.rows) continue;
          if (q.z() < zbuf.at<float>(v, u)) {
            zbuf.at<float>(v, u) = static_cast<float>(q.z());
            out.at<float>(v, u) = b;
          }
        }
    }
  return out;
}

cv::Mat staticWeights(const cv::Mat& scores) {
  if (scores.empty()) return {};
  cv::Mat w;
  cv::subtract(cv::Scalar(1.0), scores, w);
  return w;
}

}  // namespace ff
