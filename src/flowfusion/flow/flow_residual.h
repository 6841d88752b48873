#pragma once
// Ego flow and flow residual (paper Eqs. 8-9; docs/design.md).
#include <opencv2/core.hpp>
#include <vector>

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

// The flow residual of a pixel were it static at the best of several depths: per pixel the smallest
// flowResidual over the ego flows of `depths` (CV_32FC1 each, of the camera's size; a depth that is
// invalid there leaves the pixel to the others), NaN where none gives a residual. For a pixel whose
// own depth is unknown (a hole in the sensor's depth): whether any of the surfaces around it would
// move in the image as it does. Throws InputError on an empty list or a depth of another size.
cv::Mat smallestFlowResidual(const FlowField& flow, const std::vector<cv::Mat>& depths,
                             const CameraIntrinsics& camera, const SE3& T_cam_b_cam_a);

// r_F with the frame's systematic part taken out: an affine field c + A x, fitted to the residual
// vectors (optical flow - ego flow) of the valid pixels on a 4-pixel grid by a Cauchy IRLS of scale
// scale_px from the zero field (6 iterations), is subtracted before the length is taken. A small error of the
// camera's rotation, the rolling shutter and the colour-depth offset under rotation shift the
// whole static background by a smooth field of a few pixels, which flowResidual counts as motion
// everywhere; a mover covering a minority of the view stays out of the robust fit. Only for the
// residual against the camera's own motion: against another motion (a mover's) the background is
// the majority and would be fitted away. Same validity and size as flowResidual; scale_px > 0.
cv::Mat flowResidualWithoutAffine(const FlowField& flow, const cv::Mat& ego_flow, double scale_px);

// flowResidualWithoutAffine's fit with the parallax of a small error t of the camera's translation
// added: iz (fx t_x - (u - c_x) t_z, fy t_y - (v - c_y) t_z) at the pixel's inverse depth iz (`depth`,
// CV_32FC1, and `camera` of the ego flow's size; pixels without depth only take the affine part).
// On blurred frames under fast rotation the odometry's translation can be off by 1-2 cm, which
// moves near surfaces by several pixels more than far ones: a field no affine fit takes out. The
// rotation's error is the affine part's (to first order). A mover near the camera could take the
// parallax term for itself, so the pixels of `movers` (CV_8UC1, non-zero; optional) stay out of the
// fit. Same validity and size as flowResidual.
cv::Mat flowResidualWithoutPoseError(const FlowField& flow, const cv::Mat& ego_flow, const cv::Mat& depth,
                                     const CameraIntrinsics& camera, double scale_px, const cv::Mat& movers = {});

// Pixels whose forward flow (A to B) the backward flow (B to A) does not bring back:
// |forward(x) + backward(x + forward(x))| above tolerance_px plus 5 % of |forward(x)| (backward
// sampled bilinearly, replicated past the border). There the flow matched nothing reliable (motion
// blur, occlusion, a textureless patch), so its residual is no evidence. CV_8U, 255 =
// inconsistent. Both fields CV_32FC2 of one size; tolerance_px >= 0.
cv::Mat inconsistentFlow(const FlowField& forward, const FlowField& backward, double tolerance_px);

// Pixels of A hidden in B: where A's point, moved by T_cam_b_cam_a, lies behind B's depth (the
// smallest valid depth over the 3x3 pixels it lands on) by more than margin times its depth in B.
// There B saw something nearer (a mover passing in front, or a nearer surface by parallax), so
// the optical flow from A to B matched that, not the point. CV_8U, 255 = hidden; 0 where A has no
// depth, the point leaves B's image or B has no depth there. depth_a and depth_b: CV_32F metres of
// the camera's size.
cv::Mat hiddenIn(const cv::Mat& depth_a, const cv::Mat& depth_b, const CameraIntrinsics& camera,
                 const SE3& T_cam_b_cam_a, double margin);

// The flow from a frame to the frame steps.size() back, chained through the frames between:
// steps[0] from the frame to its previous one, steps[i] from that one to its own previous, each
// sampled (bilinear) where the chain has got to. NaN where the chain leaves the image. All the
// steps of one size (CV_32FC2); at least one.
FlowField chainFlows(const std::vector<const FlowField*>& steps);

// The larger of two flow residuals of one frame (CV_32FC1 each, one size): r_F where `other` is
// NaN or empty, NaN where r_F is (out of view of the previous frame).
cv::Mat largerResidual(const cv::Mat& r_F, const cv::Mat& other);

// The median of the finite values of a CV_32FC1 image (NaN when it has none).
double finiteMedian(const cv::Mat& values);

// r_F relative to the frame's own flow error: when the median r_F over the frame exceeds
// `typical_px`, the flow failed on the frame as a whole (motion blur, a large rotation), not on a
// mover, which covers a minority of the view; r_F is scaled by typical_px / median, so only what
// stands out from the frame's error counts as motion. Unchanged below it; `typical_px` <= 0 = off.
cv::Mat relativeToFrameError(const cv::Mat& r_F, double typical_px);

}  // namespace ff
