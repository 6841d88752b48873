#pragma once
// The written dynamic mask without small marks inside the view. On real frames the scores leave
// marks of one or two clusters where blur, a depth edge or the colour-depth time offset gives a
// static cluster a residual of its own, frame after frame, with nothing around it marked. A mover
// within the depth sensor's range covers more of the image (a person at 6 m about 2 % of it), and
// one entering the view is a slice of any size at first, but across the image's border.
#include <opencv2/core.hpp>

namespace ff {

// Clears (0) every 8-connected dynamic region of `mask` (CV_8UC1, > 0 = dynamic) that holds fewer
// than `min_area_share` (in [0, 1); 0 keeps all) of the image's pixels and touches no image border.
// Throws InputError on an empty mask, another type or a share outside [0, 1).
void dropSmallInteriorRegions(cv::Mat& mask, double min_area_share);

}  // namespace ff
