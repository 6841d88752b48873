#include "flowfusion/flow/flow_motion.h"

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "flowfusion/core/error.h"

namespace ff {

void validate(const ConsensusConfig& c) {
  if (c.grid_step < 1) throw InputError("consensus.grid_step must be at least 1 (pixels)");
  if (!(c.inlier_px > 0)) throw InputError("consensus.inlier_px must be > 0 (pixels)");
  if (c.ransac_iterations < 1) throw InputError("consensus.ransac_iterations must be at least 1");
  if (!(c.min_gain >= 0 && c.min_gain <= 1)) throw InputError("consensus.min_gain must be in [0, 1]");
}

FlowCorrespondences sampleFlowCorrespondences(const FlowField& flow, const cv::Mat& depth_a,
                                              const CameraIntrinsics& camera, int step) {
  if (flow.uv.type() != CV_32FC2 || depth_a.type() != CV_32FC1 || flow.uv.size() != depth_a.size() ||
      depth_a.cols != camera.width || depth_a.rows != camera.height)
    throw InputError("sampleFlowCorrespondences: flow (CV_32FC2), depth (CV_32F) and camera sizes must match");
  FlowCorrespondences c;
  for (int v = step / 2; v < depth_a.rows; v += step)
    for (int u = step / 2; u < depth_a.cols; u += step) {
      const float z = depth_a.at<float>(v, u);
      const cv::Vec2f f = flow.uv.at<cv::Vec2f>(v, u);
      if (!(z > 0) || !std::isfinite(f[0]) || !std::isfinite(f[1])) continue;
      const double ub = u + f[0], vb = v + f[1];
      if (!camera.inImage(ub, vb)) continue;
      const Eigen::Vector3d p = camera.backproject(u, v, z);
      c.points_a.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
      c.pixels_b.emplace_back(static_cast<float>(ub), static_cast<float>(vb));
    }
  return c;
}

namespace {

// Whether T_b_a takes correspondence i's point within sqrt(r2) pixels of its flow target.
bool explains(const FlowCorrespondences& c, size_t i, const CameraIntrinsics& camera, const SE3& T_b_a, double r2) {
  const cv::Point3f& p = c.points_a[i];
  const Eigen::Vector3d q = T_b_a * Eigen::Vector3d(p.x, p.y, p.z);
  if (q.z() <= 0) return false;
  const Eigen::Vector2d uv = camera.project(q);
  const double du = uv.x() - c.pixels_b[i].x, dv = uv.y() - c.pixels_b[i].y;
  return du * du + dv * dv < r2;
}

SE3 fromRvecTvec(const cv::Mat& rvec, const cv::Mat& tvec) {
  cv::Mat R;
  cv::Rodrigues(rvec, R);
  Eigen::Matrix3d R_e;
  Eigen::Vector3d t_e;
  cv::cv2eigen(R, R_e);
  cv::cv2eigen(tvec, t_e);
  SE3 T = SE3::Identity();
  T.linear() = R_e;
  T.translation() = t_e;
  return orthonormalized(T);
}

}  // namespace

int countFlowInliers(const FlowCorrespondences& c, const CameraIntrinsics& camera, const SE3& T_b_a,
                     double inlier_px) {
  int n = 0;
  for (size_t i = 0; i < c.size(); ++i) n += explains(c, i, camera, T_b_a, inlier_px * inlier_px);
  return n;
}

FlowMotion estimateFlowMotion(const FlowCorrespondences& c, const CameraIntrinsics& camera,
                              const ConsensusConfig& config) {
  FlowMotion m;
  // Fewer samples than this say nothing about which motion dominates the view.
  constexpr size_t kMinSamples = 30;
  if (c.size() < kMinSamples) return m;
  cv::Mat K;
  cv::eigen2cv(camera.K(), K);
  cv::Mat rvec, tvec;
  if (!cv::solvePnPRansac(c.points_a, c.pixels_b, K, cv::noArray(), rvec, tvec, false, config.ransac_iterations,
                          static_cast<float>(config.inlier_px), 0.999, cv::noArray(), cv::SOLVEPNP_AP3P))
    return m;
  // Least squares (Levenberg-Marquardt on the reprojection error) over all the correspondences
  // the RANSAC motion explains, not only its consensus set's final count.
  std::vector<cv::Point3f> in_a;
  std::vector<cv::Point2f> in_b;
  const SE3 T_ransac = fromRvecTvec(rvec, tvec);
  for (size_t i = 0; i < c.size(); ++i) {
    if (!explains(c, i, camera, T_ransac, config.inlier_px * config.inlier_px)) continue;
    in_a.push_back(c.points_a[i]);
    in_b.push_back(c.pixels_b[i]);
  }
  constexpr size_t kMinInliers = 6;
  if (in_a.size() < kMinInliers) return m;
  cv::solvePnPRefineLM(in_a, in_b, K, cv::noArray(), rvec, tvec);
  m.T_b_a = fromRvecTvec(rvec, tvec);
  m.inliers = countFlowInliers(c, camera, m.T_b_a, config.inlier_px);
  m.ok = true;
  return m;
}

std::optional<SE3> flowConsensusMotion(const FlowField& flow, const cv::Mat& depth_a, const CameraIntrinsics& camera,
                                       const SE3& T_b_a_odometry, const ConsensusConfig& config) {
  const FlowCorrespondences c = sampleFlowCorrespondences(flow, depth_a, camera, config.grid_step);
  const double n = static_cast<double>(c.size());
  const int explained = countFlowInliers(c, camera, T_b_a_odometry, config.inlier_px);
  // RANSAC cannot win by min_gain when the odometry already explains this much.
  if (explained >= (1.0 - config.min_gain) * n) return std::nullopt;
  const FlowMotion m = estimateFlowMotion(c, camera, config);
  if (!m.ok || m.inliers < explained + config.min_gain * n) return std::nullopt;
  return m.T_b_a;
}

}  // namespace ff
