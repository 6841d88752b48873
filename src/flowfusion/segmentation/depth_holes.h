#pragma once
// The dynamic mask over pixels without depth. Such a pixel carries no evidence of its own: no depth
// residual, no ego-flow, no cluster. A real sensor leaves them where a mover comes nearer than its
// range (a hand, a box held up to the camera) or where its surface is dark or shiny, and the mask
// then shows the mover with a hole where most of it is. A hole becomes dynamic when most of the
// valid pixels around it are; a hole beside a mover (the shadow of its edge, a black screen behind
// it) borders the static world as much and keeps the label the scores gave it. A hole whose own
// image motion no static surface around it explains, beside a mover, is the mover's (movingHoles).
#include <opencv2/core.hpp>

#include "flowfusion/core/rgbd_frame.h"
#include "flowfusion/core/sensor_band.h"

namespace ff {

// Marks (255) every 4-connected region of `depth` without a valid value (<= 0 or NaN; CV_32F,
// metres) in `mask` (CV_8U, same size, > 0 = dynamic) when at least `min_dynamic_share` (in (0, 1])
// of its 4-neighbours with depth are dynamic there; the image border is no neighbour. The pixels of
// `band` (CV_8U, > 0; the sensor's band, SensorBand::pixels; optional) are never marked: a hole
// that runs into the band is judged as it is, but the band beside a mover at the image's edge is
// the static world's as often (its true label is unknown to the sensor). Other pixels keep theirs.
// Throws InputError on mismatched sizes or types or a share outside (0, 1].
void fillDepthHoles(cv::Mat& mask, const cv::Mat& depth, double min_dynamic_share, const cv::Mat& band = {});

// The nearest and the farthest valid depth within a window_px x window_px square around each pixel
// of `depth` (CV_32F, metres), 0 where the square has none: what may lie at a pixel without depth,
// from the surfaces around it. window_px odd, >= 3.
struct DepthAround {
  cv::Mat nearest, farthest;  // CV_32F, depth's size
};
DepthAround depthAround(const cv::Mat& depth, int window_px);

// The pixels without depth whose own motion can tell (CV_8U, 255; empty when none): off `band`
// (CV_8U, > 0, depth's size, SensorBand::pixels; empty: none left out) and on surfaces neither
// black nor white in `intensity` (CV_32F, [0, 1], depth's size; a black screen's or a window's flow
// is filled in from around it and means nothing), in regions at least kHoleMinWidthPx wide (the
// flow's spill over a mover's edge is narrower).
cv::Mat holesToTest(const cv::Mat& depth, const cv::Mat& intensity, const cv::Mat& band);
constexpr float kHoleMaxIntensity = 0.9f;  // white (a window); black is kBlackGrey
constexpr int kHoleMinWidthPx = 7;

// Those of `holes` (holesToTest's) that move on their own (CV_8U, 255; empty when none): where
// `static_residual_px` (CV_32F of their size: the flow residual were the pixel static at the best
// depth around it, smallestFlowResidual; NaN unknown) exceeds min_flow_px and `flow_inconsistent`
// (CV_8U, optional) does not hold, in regions at least kHoleMinWidthPx wide.
cv::Mat holesMovingOnTheirOwn(const cv::Mat& holes, const cv::Mat& static_residual_px, const cv::Mat& flow_inconsistent,
                              double min_flow_px);

// The pixels of `band` (CV_8U, > 0: the sensor's band; empty: none) without depth (`depth`, CV_32F,
// metres) within reach_px (> 0) rows and columns of a marked pixel of `mask` (CV_8U, > 0 =
// dynamic), CV_8U 255, depth's size: where a mover at the image's edge goes on without depth,
// whatever its flow (a person standing at the edge barely moves there). clearBandHolesOfWorldColour
// then keeps its colours' part.
cv::Mat bandBesideMovers(const cv::Mat& band, const cv::Mat& mask, const cv::Mat& depth, int reach_px);

// Clears the pixels of `moving_holes` (CV_8U, holesMovingOnTheirOwn's at the mask's size, with
// bandBesideMovers') in `band` (CV_8U, > 0: the sensor's band; empty: nothing is cleared) whose
// colour is likelier the static world's than the written movers': per 8-connected region of them,
// BGR histograms (kColourBins a channel, one count added to every bin) of the pixels with depth
// (`depth`, CV_32F) within kColourRingPx of it, split by `mask` (CV_8U, > 0 = dynamic); `color`
// CV_8UC3 BGR. In the band nothing has depth: beside a mover at the image's edge its flow spills
// over the room there as readily as over the mover's own part, and the room keeps the room's
// colours. A region with no written pixel around it is left as it is (markHolesBesideMovers will
// not take it).
void clearBandHolesOfWorldColour(cv::Mat& moving_holes, const cv::Mat& band, const cv::Mat& mask, const cv::Mat& color,
                                 const cv::Mat& depth);
constexpr int kColourBins = 8;
constexpr int kColourRingPx = 15;

// Marks (255) in `mask` (CV_8U, > 0 = dynamic) the 8-connected regions of `moving_holes` (CV_8U, the
// mask's size; holesMovingOnTheirOwn's) that touch a marked pixel or lie within 2 pixels of one. A
// box held nearer than the sensor's range moves with its own sides that have depth, a person half
// in the sensor's band with the half outside it; a black screen's or a window's hole, whose flow is
// filled in from the static frame around it, lies beside no mover.
void markHolesBesideMovers(cv::Mat& mask, const cv::Mat& moving_holes);

}  // namespace ff
