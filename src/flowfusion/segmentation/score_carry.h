#pragma once
// A frame's dynamic scores carried into the next frame along the camera's motion: the weights of
// the next frame's first odometry and the temporal prior of its scores.
#include <opencv2/core.hpp>

#include "flowfusion/core/camera.h"
#include "flowfusion/core/se3.h"

namespace ff {

// Each previous pixel's score (prev_scores, CV_32F) splatted to where T_cur_prev takes it with
// its depth (prev_depth, CV_32F metres, the scores' size, `camera` at that size); the nearest
// surface wins, `fill` where nothing lands.
cv::Mat carryScores(const cv::Mat& prev_scores, const cv::Mat& prev_depth, const CameraIntrinsics& camera,
                    const SE3& T_cur_prev, float fill);

// 1 - scores: how far each pixel counts as static (empty for empty scores).
cv::Mat staticWeights(const cv::Mat& scores);

}  // namespace ff
