#include <gtest/gtest.h>

#include <limits>

#include "flowfusion/core/error.h"
#include "flowfusion/segmentation/depth_holes.h"

namespace ff {
namespace {

// A 40 x 30 image with depth everywhere (2 m), a dynamic square (rows and columns 5-19) and
// nothing else dynamic.
struct Scene {
  cv::Mat depth = cv::Mat(30, 40, CV_32F, cv::Scalar(2.f));
  cv::Mat mask = cv::Mat(30, 40, CV_8U, cv::Scalar(0));
  Scene() { mask(cv::Rect(5, 5, 15, 15)).setTo(255); }
  void hole(const cv::Rect& r, float value = 0.f) { depth(r).setTo(value); }
};

TEST(DepthHoles, AHoleInsideAMoverBecomesDynamic) {
  Scene s;
  s.hole(cv::Rect(9, 9, 5, 5));                                   // within the square
  s.hole(cv::Rect(30, 10, 4, 4), std::numeric_limits<float>::quiet_NaN());  // in the static world
  s.mask(cv::Rect(9, 9, 5, 5)).setTo(0);
  s.mask(cv::Rect(31, 11, 2, 2)).setTo(255);  // what the scores marked in a static hole stays
  fillDepthHoles(s.mask, s.depth, 0.8);
  EXPECT_EQ(cv::countNonZero(s.mask(cv::Rect(9, 9, 5, 5))), 25);
  EXPECT_EQ(cv::countNonZero(s.mask(cv::Rect(30, 10, 4, 4))), 4);
  EXPECT_EQ(cv::countNonZero(s.mask), 15 * 15 + 4);
}

TEST(DepthHoles, AHoleBesideAMoverStaysStaticAndTheImageBorderIsNoNeighbour) {
  Scene s;
  // Beside the square: 3 of its 18 neighbours with depth (its left side) are the square's.
  s.hole(cv::Rect(20, 8, 6, 3));
  fillDepthHoles(s.mask, s.depth, 0.8);
  EXPECT_EQ(cv::countNonZero(s.mask(cv::Rect(20, 8, 6, 3))), 0);
  // A mover at the image's left edge with a hole there: its neighbours with depth are all dynamic.
  Scene edge;
  edge.mask.setTo(0);
  edge.mask(cv::Rect(0, 5, 15, 15)).setTo(255);
  edge.hole(cv::Rect(0, 9, 4, 5));
  edge.mask(cv::Rect(0, 9, 4, 5)).setTo(0);
  fillDepthHoles(edge.mask, edge.depth, 1.0);
  EXPECT_EQ(cv::countNonZero(edge.mask(cv::Rect(0, 9, 4, 5))), 20);
}

TEST(DepthHoles, TheShareDecidesAndAFrameWithoutDepthIsLeftAsItIs) {
  Scene s;
  s.hole(cv::Rect(20, 8, 6, 3));  // 3 of its 18 neighbours with depth are dynamic
  cv::Mat loose = s.mask.clone();
  fillDepthHoles(loose, s.depth, 0.15);
  EXPECT_EQ(cv::countNonZero(loose(cv::Rect(20, 8, 6, 3))), 18);
  cv::Mat empty_depth(30, 40, CV_32F, cv::Scalar(0.f));
  cv::Mat mask = s.mask.clone();
  fillDepthHoles(mask, empty_depth, 0.8);
  EXPECT_EQ(cv::countNonZero(mask != s.mask), 0);
}

TEST(DepthHoles, TheSensorsBandIsNeverMarkedButCountsInItsHole) {
  // A face without depth from the square's right side to a band of 4 columns at the image's right
  // edge. Its neighbours with depth: 6 of the square's, 32 static ones above and below the face and
  // 24 beside the band (a share of 0.10).
  Scene s;
  s.hole(cv::Rect(36, 0, 4, 30));  // the band
  s.hole(cv::Rect(20, 8, 16, 6));  // the face
  cv::Mat band(30, 40, CV_8U, cv::Scalar(0));
  band.colRange(36, 40).setTo(255);
  cv::Mat without = s.mask.clone();
  fillDepthHoles(without, s.depth, 0.09);
  EXPECT_EQ(cv::countNonZero(without.colRange(36, 40)), 4 * 30) << "the whole band marked with the face";
  cv::Mat with = s.mask.clone();
  fillDepthHoles(with, s.depth, 0.09, band);
  EXPECT_EQ(cv::countNonZero(with(cv::Rect(20, 8, 16, 6))), 16 * 6);
  EXPECT_EQ(cv::countNonZero(with.colRange(36, 40)), 0) << "the band stays as the scores left it";
  cv::Mat strict = s.mask.clone();
  fillDepthHoles(strict, s.depth, 0.15, band);
  EXPECT_EQ(cv::countNonZero(strict(cv::Rect(20, 8, 16, 6))), 0) << "the band's neighbours still count";
  EXPECT_THROW(fillDepthHoles(with, s.depth, 0.15, cv::Mat(10, 10, CV_8U)), InputError);
}

TEST(DepthHoles, RejectsMismatchedImagesAndShares) {
  Scene s;
  cv::Mat small(10, 10, CV_8U, cv::Scalar(0));
  EXPECT_THROW(fillDepthHoles(small, s.depth, 0.8), InputError);
  cv::Mat wrong_depth(30, 40, CV_16U, cv::Scalar(0));
  EXPECT_THROW(fillDepthHoles(s.mask, wrong_depth, 0.8), InputError);
  EXPECT_THROW(fillDepthHoles(s.mask, s.depth, 0.0), InputError);
  EXPECT_THROW(fillDepthHoles(s.mask, s.depth, 1.5), InputError);
}

TEST(DepthAround, GivesTheNearestAndFarthestValidDepthWithinTheWindow) {
  cv::Mat depth(60, 80, CV_32F, cv::Scalar(2.f));
  depth(cv::Rect(30, 0, 10, 60)).setTo(1.f);
  depth(cv::Rect(40, 10, 5, 5)).setTo(0.f);
  const DepthAround around = depthAround(depth, 11);
  EXPECT_FLOAT_EQ(around.nearest.at<float>(12, 42), 1.f);
  EXPECT_FLOAT_EQ(around.farthest.at<float>(12, 42), 2.f);
  EXPECT_FLOAT_EQ(around.nearest.at<float>(40, 70), 2.f);
  const DepthAround nothing = depthAround(cv::Mat(60, 80, CV_32F, cv::Scalar(0.f)), 11);
  EXPECT_EQ(cv::countNonZero(nothing.nearest), 0);
  EXPECT_EQ(cv::countNonZero(nothing.farthest), 0);
  EXPECT_THROW(depthAround(depth, 10), InputError);
  EXPECT_THROW(depthAround(cv::Mat(60, 80, CV_16U), 11), InputError);
}

// A 60 x 80 frame at 2 m with holes whose flow residual (were they static) is 8 px, grey 0.5.
struct HoleScene {
  cv::Mat depth = cv::Mat(60, 80, CV_32F, cv::Scalar(2.f));
  cv::Mat intensity = cv::Mat(60, 80, CV_32F, cv::Scalar(0.5f));
  cv::Mat residual = cv::Mat(60, 80, CV_32F, cv::Scalar(0.5f));
  void hole(const cv::Rect& r, float residual_px = 8.f) {
    depth(r).setTo(0.f);
    residual(r).setTo(residual_px);
  }
};

TEST(MovingHoles, TestsWideHolesOnGreySurfacesOutsideTheBandAndKeepsThoseTheFlowMoves) {
  HoleScene s;
  s.hole(cv::Rect(10, 10, 12, 12));                 // moves
  s.hole(cv::Rect(30, 10, 12, 12));                 // black
  s.intensity(cv::Rect(30, 10, 12, 12)).setTo(0.05f);
  s.hole(cv::Rect(50, 10, 12, 12), 2.f);            // explained by a static depth
  s.hole(cv::Rect(10, 35, 4, 20));                  // a spill 4 px wide
  s.hole(cv::Rect(30, 35, 12, 12));                 // moves, half its flow inconsistent
  cv::Mat inconsistent(60, 80, CV_8U, cv::Scalar(0));
  inconsistent(cv::Rect(30, 35, 12, 6)).setTo(255);
  s.hole(cv::Rect(72, 0, 8, 60));                   // the sensor's band
  const cv::Mat holes = holesToTest(s.depth, s.intensity, SensorBand::of(s.depth).pixels(s.depth.size()));
  ASSERT_FALSE(holes.empty());
  EXPECT_EQ(cv::countNonZero(holes), 3 * 144) << "the first, the third and the fifth";
  EXPECT_EQ(cv::countNonZero(holes(cv::Rect(30, 10, 12, 12))), 0) << "a black screen";
  EXPECT_EQ(cv::countNonZero(holes(cv::Rect(10, 35, 4, 20))), 0) << "narrower than the opening";
  EXPECT_EQ(cv::countNonZero(holes(cv::Rect(72, 0, 8, 60))), 0) << "the band";
  const cv::Mat with_band = holesToTest(s.depth, s.intensity, cv::Mat());
  EXPECT_EQ(cv::countNonZero(with_band), 3 * 144 + 8 * 60) << "no band given: the band is tested too";
  const cv::Mat moving = holesMovingOnTheirOwn(holes, s.residual, inconsistent, 4.0);
  ASSERT_FALSE(moving.empty());
  EXPECT_EQ(cv::countNonZero(moving(cv::Rect(10, 10, 12, 12))), 144);
  EXPECT_EQ(cv::countNonZero(moving(cv::Rect(50, 10, 12, 12))), 0) << "explained";
  EXPECT_EQ(cv::countNonZero(moving(cv::Rect(30, 35, 12, 12))), 0) << "6 rows past the flow check: below 7";
  EXPECT_EQ(cv::countNonZero(moving), 144);
  EXPECT_TRUE(holesMovingOnTheirOwn(holes, s.residual, {}, 10.0).empty());
  HoleScene white;
  white.hole(cv::Rect(10, 10, 12, 12));
  white.intensity.setTo(0.95f);
  const cv::Mat no_band(60, 80, CV_8U, cv::Scalar(0));
  EXPECT_TRUE(holesToTest(white.depth, white.intensity, no_band).empty()) << "a window";
  EXPECT_THROW(holesToTest(s.depth, cv::Mat(30, 40, CV_32F), no_band), InputError);
  EXPECT_THROW(holesToTest(s.depth, s.intensity, cv::Mat(30, 40, CV_8U)), InputError);
  EXPECT_THROW(holesMovingOnTheirOwn(holes, cv::Mat(30, 40, CV_32F), {}, 4.0), InputError);
}

TEST(MovingHoles, MarksOnlyTheRegionsBesideAMover) {
  cv::Mat mask(60, 80, CV_8U, cv::Scalar(0));
  mask(cv::Rect(10, 10, 10, 20)).setTo(255);
  cv::Mat moving(60, 80, CV_8U, cv::Scalar(0));
  moving(cv::Rect(20, 10, 8, 8)).setTo(255);  // touches the mover
  moving(cv::Rect(12, 31, 8, 8)).setTo(255);  // 2 px below it
  moving(cv::Rect(50, 10, 8, 8)).setTo(255);  // apart
  markHolesBesideMovers(mask, moving);
  EXPECT_EQ(cv::countNonZero(mask(cv::Rect(20, 10, 8, 8))), 64);
  EXPECT_EQ(cv::countNonZero(mask(cv::Rect(12, 31, 8, 8))), 64);
  EXPECT_EQ(cv::countNonZero(mask(cv::Rect(50, 10, 8, 8))), 0);
  EXPECT_EQ(cv::countNonZero(mask), 200 + 128);
  cv::Mat small(10, 10, CV_8U, cv::Scalar(0));
  EXPECT_THROW(markHolesBesideMovers(small, moving), InputError);
}

TEST(MovingHoles, InTheBandKeepsTheMoversColourAndClearsTheRooms) {
  // A grey room with depth, a green mover at columns 40-59 (written) and the sensor's band at
  // columns 60-79 without depth: the mover goes on into it in rows 10-29, below that the band is
  // the room. The flow moves in the band's rows 10-49, the room's part spilled over from the mover.
  const cv::Vec3b grey(128, 128, 128), green(0, 160, 0);
  cv::Mat color(60, 80, CV_8UC3, grey), depth(60, 80, CV_32F, cv::Scalar(2.f));
  cv::Mat band(60, 80, CV_8U, cv::Scalar(0)), mask(60, 80, CV_8U, cv::Scalar(0));
  band.colRange(60, 80).setTo(255);
  depth.setTo(0.f, band);
  color(cv::Rect(40, 10, 40, 20)).setTo(green);
  mask(cv::Rect(40, 10, 20, 20)).setTo(255);
  cv::Mat moving(60, 80, CV_8U, cv::Scalar(0));
  moving(cv::Rect(60, 10, 20, 40)).setTo(255);
  moving(cv::Rect(20, 40, 10, 10)).setTo(255);  // a hole off the band: not this rule's
  clearBandHolesOfWorldColour(moving, band, mask, color, depth);
  EXPECT_EQ(cv::countNonZero(moving(cv::Rect(60, 10, 20, 20))), 400) << "the mover's part in the band";
  EXPECT_EQ(cv::countNonZero(moving(cv::Rect(60, 30, 20, 20))), 0) << "the room's, the flow spilled";
  EXPECT_EQ(cv::countNonZero(moving(cv::Rect(20, 40, 10, 10))), 100);

  // Without a written mover around a region, or without a band, nothing is cleared.
  cv::Mat apart = cv::Mat(60, 80, CV_8U, cv::Scalar(0));
  apart(cv::Rect(60, 30, 20, 20)).setTo(255);
  clearBandHolesOfWorldColour(apart, band, cv::Mat(60, 80, CV_8U, cv::Scalar(0)), color, depth);
  EXPECT_EQ(cv::countNonZero(apart), 400);
  clearBandHolesOfWorldColour(apart, {}, mask, color, depth);
  EXPECT_EQ(cv::countNonZero(apart), 400);
  EXPECT_THROW(clearBandHolesOfWorldColour(apart, band, mask, cv::Mat(60, 80, CV_8UC1), depth), InputError);
}

TEST(MovingHoles, TheBandBesideAWrittenMoverIsTestedByColourWhateverItsFlow) {
  // The scene above without any flow: the mover stands at the edge. The band's pixels within the
  // reach of the written mover are tested, the room's part of them cleared by its colour; a band
  // pixel beyond the reach, and a pixel with depth, are not taken.
  const cv::Vec3b grey(128, 128, 128), green(0, 160, 0);
  cv::Mat color(60, 80, CV_8UC3, grey), depth(60, 80, CV_32F, cv::Scalar(2.f));
  cv::Mat band(60, 80, CV_8U, cv::Scalar(0)), mask(60, 80, CV_8U, cv::Scalar(0));
  band.colRange(60, 80).setTo(255);
  depth.colRange(60, 80).setTo(0.f);
  band.rowRange(0, 4).setTo(255);  // a top band whose pixels have depth here: never taken
  color(cv::Rect(40, 10, 40, 20)).setTo(green);
  mask(cv::Rect(40, 10, 20, 20)).setTo(255);
  const int reach_px = 12;
  cv::Mat beside = bandBesideMovers(band, mask, depth, reach_px);
  EXPECT_EQ(cv::countNonZero(beside.colRange(0, 60)), 0) << "only the band's pixels without depth";
  mask(cv::Rect(40, 0, 20, 10)).setTo(255);  // the mover reaches the top band, which has depth
  EXPECT_EQ(cv::countNonZero(bandBesideMovers(band, mask, depth, reach_px).colRange(0, 60)), 0);
  mask(cv::Rect(40, 0, 20, 10)).setTo(0);
  EXPECT_EQ(cv::countNonZero(beside(cv::Rect(60, 10, 12, 20))), 12 * 20) << "within the reach";
  EXPECT_EQ(cv::countNonZero(beside.colRange(73, 80)), 0) << "beyond the reach";
  EXPECT_GT(cv::countNonZero(beside(cv::Rect(60, 30, 12, 12))), 0) << "the room beside the mover too";
  clearBandHolesOfWorldColour(beside, band, mask, color, depth);
  markHolesBesideMovers(mask, beside);
  EXPECT_EQ(cv::countNonZero(mask(cv::Rect(60, 10, 12, 20))), 12 * 20) << "the mover's part in the band";
  EXPECT_EQ(cv::countNonZero(mask(cv::Rect(60, 30, 20, 30))), 0) << "the room's part";

  // No written mover, or no band: nothing.
  EXPECT_EQ(cv::countNonZero(bandBesideMovers(band, cv::Mat(60, 80, CV_8U, cv::Scalar(0)), depth, reach_px)), 0);
  EXPECT_EQ(cv::countNonZero(bandBesideMovers({}, mask, depth, reach_px)), 0);
  EXPECT_THROW(bandBesideMovers(band, mask, depth, 0), InputError);
  EXPECT_THROW(bandBesideMovers(band, mask, cv::Mat(60, 80, CV_8U), reach_px), InputError);
}

}  // namespace
}  // namespace ff
