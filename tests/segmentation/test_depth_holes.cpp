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

TEST(DepthHoles, RejectsMismatchedImagesAndShares) {
  Scene s;
  cv::Mat small(10, 10, CV_8U, cv::Scalar(0));
  EXPECT_THROW(fillDepthHoles(small, s.depth, 0.8), InputError);
  cv::Mat wrong_depth(30, 40, CV_16U, cv::Scalar(0));
  EXPECT_THROW(fillDepthHoles(s.mask, wrong_depth, 0.8), InputError);
  EXPECT_THROW(fillDepthHoles(s.mask, s.depth, 0.0), InputError);
  EXPECT_THROW(fillDepthHoles(s.mask, s.depth, 1.5), InputError);
}

}  // namespace
}  // namespace ff
