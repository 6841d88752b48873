#include "flowfusion/segmentation/held_movers.h"

#include <cmath>

#include "flowfusion/segmentation/score_carry.h"

namespace ff {

cv::Mat HeldMovers::carried(const cv::Mat& previous_depth, double previous_timestamp, const CameraIntrinsics& camera,
                            const SE3& T_prev_cur, const cv::Mat& depth, double timestamp,
                            const cv::Mat& map_agreement) const {
  if (!enabled() || hold_.empty() || timestamp_ != previous_timestamp || map_agreement.empty()) return {};
  const SE3 T_cur_prev = T_prev_cur.inverse();
  cv::Mat hold = carryScores(hold_, previous_depth, camera, T_cur_prev, 0.f);
  const cv::Mat held_depth = carryScores(previous_depth, previous_depth, camera, T_cur_prev, 0.f);
  hold *= std::exp(-(timestamp - previous_timestamp) / hold_s_);
  for (int v = 0; v < hold.rows; ++v) {
    float* h = hold.ptr<float>(v);
    const float* z = depth.ptr<float>(v);
    const float* z_held = held_depth.ptr<float>(v);
    for (int u = 0; u < hold.cols; ++u)
      if (!(z[u] > 0) || !(z_held[u] > 0) || std::abs(z[u] - z_held[u]) > kLetGoFraction * z_held[u] + kLetGoMetres)
        h[u] = 0.f;
  }
  const cv::Mat compared_and_disagrees = map_agreement < 0.5f;  // false where NaN (nothing to compare with) or 1
  hold.setTo(0.f, ~compared_and_disagrees);
  return hold;
}

void HeldMovers::remember(const cv::Mat& carried_hold, const cv::Mat& seen_moving, double timestamp) {
  if (!enabled()) return;
  cv::Mat seen;
  seen_moving.convertTo(seen, CV_32F, 1.0 / 255);
  seen.setTo(1.f, seen > 0);
  hold_ = carried_hold.empty() ? seen : cv::max(carried_hold, seen);
  timestamp_ = timestamp;
}

}  // namespace ff
