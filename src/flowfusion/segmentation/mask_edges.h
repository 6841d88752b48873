#pragma once
// The written dynamic mask's edge at the input's resolution. The scores are per cluster at the
// segmentation level (half size) and are scaled up pixel for pixel, so the mask's edge lies a pixel
// or two off the mover's silhouette, and the pixels without depth there (the sensor's shadow beside
// a near surface, the grazing edge of the mover itself) take whichever label the half-size pixel
// had. Each pixel near the edge joins the side it resembles: across a depth step, the side whose
// depth it is nearer; without depth of its own, the side whose colour it is nearer
// (docs/tuning.md#mask_edge_px).
#include <opencv2/core.hpp>

namespace ff {

// Reassigns every pixel of `mask` (CV_8UC1, > 0 = dynamic; written 255 or 0 where it changes) that
// has both dynamic and static pixels within `radius_px` (a square window; 0 changes nothing): with
// depth (`depth`, CV_32FC1 metres, 0 = none), to the side whose mean depth over its pixels with
// depth there is nearer to its own, where the two means differ by more than kEdgeDepthStep of its
// depth; without depth, to the side whose mean colour (`bgr`, CV_8UC3, as CIELab over 255) is
// nearer to its own, where the two means differ by more than kEdgeColourStep (none where `bgr` is
// empty). The sides are read from the mask as given. Throws InputError on mismatched sizes or
// types or a negative radius.
void refineMaskEdges(cv::Mat& mask, const cv::Mat& depth, const cv::Mat& bgr, int radius_px);

// A depth step between the two sides, relative to the pixel's depth (3 cm at 1 m: beyond the
// sensor's noise there, below a person's distance from the wall).
constexpr float kEdgeDepthStep = 0.03f;
// A colour step between the two sides: the distance of their mean CIELab colours (channels over
// 255); below it the colour cannot tell them apart.
constexpr float kEdgeColourStep = 0.05f;

}  // namespace ff
