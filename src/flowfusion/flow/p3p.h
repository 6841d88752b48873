#pragma once
// A minimal absolute-pose solver: the camera poses that put three known 3D points on three rays
// (P3P, in the manner of Lambda Twist, Persson and Nordberg, ECCV 2018), and the one of them a
// fourth correspondence agrees with best (what cv::solvePnP's SOLVEPNP_AP3P gives for four).
//
// Why: the flow split draws about 200 four-point motion hypotheses per frame pair
// (flow_motion.h); cv::solvePnP spends most of its time per call on matrix conversions,
// undistortion and Rodrigues, not on the P3P itself.
#include <Eigen/Core>
#include <array>
#include <optional>

#include "flowfusion/core/camera.h"
#include "flowfusion/core/se3.h"

namespace ff {

// Up to four poses T_cam_pts (points' frame to camera frame), each with all three points in
// front of the camera.
struct P3PSolutions {
  std::array<SE3, 4> T_cam_pts;
  int size = 0;
};

// The poses taking points[i] (metres, any frame) onto the ray through rays[i] (camera frame, any
// positive length). None for degenerate input: coincident or collinear points, parallel rays,
// values that are not finite.
P3PSolutions solveP3P(const std::array<Eigen::Vector3d, 3>& points, const std::array<Eigen::Vector3d, 3>& rays);

// Of the P3P poses of the first three correspondences (points[i] onto pixels[i] of `camera`), the
// one that projects the fourth point nearest to its pixel (and in front of the camera); none
// when there is none. Like AP3P, the candidates include the poses from the real parts of complex
// pairs of solutions: noisy pixels turn the true pose's pair complex near a double solution.
std::optional<SE3> solveP3PChoosingByFourth(const std::array<Eigen::Vector3d, 4>& points,
                                           const std::array<Eigen::Vector2d, 4>& pixels,
                                           const CameraIntrinsics& camera);

}  // namespace ff
