#pragma once
// The camera motion that the optical flow's largest rigid part explains (RANSAC over PnP on
// flow correspondences with the current frame's depth).
//
// Why: dense robust odometry converges to whatever motion its starting point and weights favour.
// When a large near object moves before anything is known of it (the first frames, an object
// walking into view), the odometry can lock onto the object, every later stage then calls the
// background dynamic and the carried scores keep the error going. The flow's rigid consensus
// does not depend on the odometry: where it explains clearly more of the image than the
// odometry's motion, the odometry is restarted from it (pipeline/segmentation_loop.h).
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "flowfusion/core/camera.h"
#include "flowfusion/core/se3.h"
#include "flowfusion/flow/optical_flow.h"

namespace ff {

struct ConsensusConfig {
  bool enabled = true;
  int grid_step = 16;           // px: flow correspondences sampled on this grid of the input image
  // px: reprojection error of a correspondence the motion explains. Loose because TUM's colour
  // and depth images are up to 20 ms apart, so a correct odometry explains the real flow less
  // exactly than the synthetic one (docs/tuning.md#consensus).
  double inlier_px = 3.0;
  int ransac_iterations = 100;  // minimal-sample (P3P) hypotheses
  // The flow's motion replaces the odometry's when it explains at least this fraction of the
  // samples more: a restart that does not help costs one more odometry (docs/tuning.md#consensus).
  double min_gain = 0.3;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(ConsensusConfig, enabled, grid_step, inlier_px, ransac_iterations,
                                                min_gain)
// Throws InputError naming the first bad setting.
void validate(const ConsensusConfig& config);

// 3D points of frame A (camera frame, metres) and where the flow takes their pixels in B.
struct FlowCorrespondences {
  std::vector<cv::Point3f> points_a;
  std::vector<cv::Point2f> pixels_b;
  size_t size() const { return points_a.size(); }
};

// Samples pixels of A on a grid of `step` pixels where A's depth is valid and the flow lands
// inside B. flow.uv and depth_a (CV_32F, metres, <= 0 invalid) have the camera's size.
FlowCorrespondences sampleFlowCorrespondences(const FlowField& flow, const cv::Mat& depth_a,
                                              const CameraIntrinsics& camera, int step);

// Correspondences T_b_a explains within `inlier_px`, the reprojection error in B.
int countFlowInliers(const FlowCorrespondences& c, const CameraIntrinsics& camera, const SE3& T_b_a,
                     double inlier_px);

struct FlowMotion {
  bool ok = false;       // false: too few correspondences or RANSAC found no motion
  SE3 T_b_a = SE3::Identity();
  int inliers = 0;       // of the correspondences, counted with countFlowInliers
};

// RANSAC (P3P hypotheses, refined on the inliers) over the correspondences.
FlowMotion estimateFlowMotion(const FlowCorrespondences& c, const CameraIntrinsics& camera,
                              const ConsensusConfig& config);

// The flow's rigid motion T_b_a when it explains at least config.min_gain of the sampled flow
// more than `T_b_a_odometry` does; none otherwise (what the system restarts its odometry from).
std::optional<SE3> flowConsensusMotion(const FlowField& flow, const cv::Mat& depth_a, const CameraIntrinsics& camera,
                                       const SE3& T_b_a_odometry, const ConsensusConfig& config);

}  // namespace ff
