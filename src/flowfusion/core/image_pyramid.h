#pragma once
// Coarse-to-fine image pyramids: level 0 is the input, level l is 2^l times smaller.
#include <opencv2/core.hpp>
#include <vector>

#include "flowfusion/core/camera.h"

namespace ff {

// 2x2 box average of a CV_32FC1 image (odd last row/column dropped).
cv::Mat downsampleIntensity(const cv::Mat& img);
// 2x2 average of the valid (> 0) depths; a pixel with no valid depth stays 0. Averaging across
// a depth discontinuity would invent surfaces, so values farther than `max_rel_spread` (relative)
// from the block's nearest depth are left out.
cv::Mat downsampleDepth(const cv::Mat& depth, float max_rel_spread = 0.05f);

struct PyramidLevel {
  cv::Mat intensity;  // CV_32FC1 in [0, 1]
  cv::Mat depth;      // CV_32FC1 metres, 0 = invalid
  cv::Mat grad_x, grad_y;   // intensity gradients (per pixel, central differences)
  cv::Mat dgrad_x, dgrad_y; // depth gradients (metres per pixel, 0 where a neighbour is invalid)
  CameraIntrinsics camera;
};

// Builds `levels` levels; gradients only from `first_gradient_level` up, since levels finer
// than the finest one used need none. Level 0 is not copied.
std::vector<PyramidLevel> buildPyramid(const cv::Mat& intensity, const cv::Mat& depth,
                                       const CameraIntrinsics& camera, int levels, int first_gradient_level = 0);

}  // namespace ff
