#pragma once
// The dynamic mask over pixels without depth. Such a pixel carries no evidence of its own: no depth
// residual, no ego-flow, no cluster. A real sensor leaves them where a mover comes nearer than its
// range (a hand, a box held up to the camera) or where its surface is dark or shiny, and the mask
// then shows the mover with a hole where most of it is. A hole becomes dynamic when most of the
// valid pixels around it are; a hole beside a mover (the shadow of its edge, a black screen behind
// it) borders the static world as much and keeps the label the scores gave it.
#include <opencv2/core.hpp>

namespace ff {

// Marks (255) every 4-connected region of `depth` without a valid value (<= 0 or NaN; CV_32F,
// metres) in `mask` (CV_8U, same size, > 0 = dynamic) when at least `min_dynamic_share` (in (0, 1])
// of its 4-neighbours with depth are dynamic there; the image border is no neighbour. Other pixels
// keep their label. Throws InputError on mismatched sizes or types or a share outside (0, 1].
void fillDepthHoles(cv::Mat& mask, const cv::Mat& depth, double min_dynamic_share);

}  // namespace ff
