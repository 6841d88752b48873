#pragma once
// The dynamic mask over pixels without depth. Such a pixel carries no evidence of its own: no depth
// residual, no ego-flow, no cluster. A real sensor leaves them where a mover comes nearer than its
// range (a hand, a box held up to the camera) or where its surface is dark or shiny, and the mask
// then shows the mover with a hole where most of it is. A hole takes the dynamic label when most
// of the valid pixels around it are dynamic; a hole beside a mover (the shadow of its edge, a black
// screen behind it) borders the static world as much and stays as it is.
#include <opencv2/core.hpp>

namespace ff {

// Labels every 4-connected region of `depth` without a valid value (<= 0 or NaN; CV_32F, metres)
// in `mask` (CV_8U, same size, 255 = dynamic): 255 when at least `min_dynamic_share` (in (0, 1])
// of its 4-neighbours with depth are dynamic there, 0 otherwise; the image border is no neighbour,
// and a region without a neighbour with depth keeps its mask. Throws InputError on mismatched
// sizes or types or a share outside (0, 1].
void fillDepthHoles(cv::Mat& mask, const cv::Mat& depth, double min_dynamic_share);

}  // namespace ff
