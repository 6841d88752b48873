#pragma once
// Ego flow and flow residual (paper Eqs. 8-9; docs/design.md).
#include <opencv2/core.hpp>

#include "flowfusion/core/camera.h"
#include "flowfusion/core/se3.h"
#include "flowfusion/flow/optical_flow.h"

namespace ff {

// Ego flow dx_e = W(x, xi) - x (Eq. 8): where pixel x of A, back-projected with its depth,
// lands in B after the camera motion T_cam_b_cam_a, minus x. CV_32FC2 in pixels; NaN where
// the depth is invalid (<= 0 or not finite) or the point falls behind camera B. Points that
// leave B's image keep their (finite) flow: the optical flow is extrapolated there too.
// For a coarser result pass a downsampled depth (downsampleDepth) with camera.atLevel(l):
// the camera's size must match depth_a's.
cv::Mat egoFlow(const cv::Mat& depth_a, const CameraIntrinsics& camera, const SE3& T_cam_b_cam_a);

// Flow residual r_F = |dx_of - dx_e| (Eq. 9), CV_32F in pixels, NaN where either is invalid or
// the ego flow leaves the image (the pixel was out of view in the other frame).
// If the sizes differ, the optical flow is resampled to the ego flow's size (resizeFlow), so
// a coarse ego flow gives a coarse residual in that level's pixels.
cv::Mat flowResidual(const FlowField& flow, const cv::Mat& ego_flow);

// The median of the finite values of a CV_32FC1 image (NaN when it has none).
double finiteMedian(const cv::Mat& values);

// r_F relative to the frame's own flow error: when the median r_F over the frame exceeds
// `typical_px`, the flow failed on the frame as a whole (motion blur, a large rotation), not on a
// mover, which covers a minority of the view; r_F is scaled by typical_px / median, so only what
// stands out from the frame's error counts as motion. Unchanged below it; `typical_px` <= 0 = off.
cv::Mat relativeToFrameError(const cv::Mat& r_F, double typical_px);

}  // namespace ff
