#include <gtest/gtest.h>

#include "flowfusion/core/error.h"
#include "flowfusion/segmentation/mask_edges.h"

namespace ff {
namespace {

// A 60 x 40 frame: a person 1.0 m away in a red shirt in columns 20-39, the grey wall 2.0 m
// behind; the mask as the half-size scores scale it up, two columns too far to the left.
struct Scene {
  cv::Mat depth = cv::Mat(40, 60, CV_32F, cv::Scalar(2.0f));
  cv::Mat bgr = cv::Mat(40, 60, CV_8UC3, cv::Scalar(128, 128, 128));
  cv::Mat mask = cv::Mat(40, 60, CV_8U, cv::Scalar(0));
  Scene() {
    depth(cv::Rect(20, 0, 20, 40)).setTo(1.0f);
    bgr(cv::Rect(20, 0, 20, 40)).setTo(cv::Scalar(40, 40, 200));
    mask(cv::Rect(18, 0, 20, 40)).setTo(255);
  }
  static cv::Mat truth() {
    cv::Mat t(40, 60, CV_8U, cv::Scalar(0));
    t(cv::Rect(20, 0, 20, 40)).setTo(255);
    return t;
  }
};

int differing(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat d;
  cv::compare(a, b, d, cv::CMP_NE);
  return cv::countNonZero(d);
}

TEST(MaskEdges, TheEdgeMovesToTheDepthStep) {
  Scene s;
  ASSERT_EQ(differing(s.mask, Scene::truth()), 4 * 40);
  refineMaskEdges(s.mask, s.depth, s.bgr, 2);
  EXPECT_EQ(differing(s.mask, Scene::truth()), 0);
  Scene no_colour;
  refineMaskEdges(no_colour.mask, no_colour.depth, cv::Mat(), 2);  // the depth alone
  EXPECT_EQ(differing(no_colour.mask, Scene::truth()), 0);
}

TEST(MaskEdges, APixelWithoutDepthJoinsTheSideOfItsColour) {
  Scene s;
  s.depth(cv::Rect(18, 0, 2, 40)).setTo(0.f);   // the sensor's shadow on the wall, marked
  s.depth(cv::Rect(20, 30, 2, 10)).setTo(0.f);  // the shirt's grazing edge ...
  s.mask(cv::Rect(18, 30, 4, 10)).setTo(0);     // ... and the shadow below it, not marked
  s.depth(cv::Rect(27, 15, 6, 10)).setTo(0.f);  // a hole in the shirt inside the mask stays
  refineMaskEdges(s.mask, s.depth, s.bgr, 2);
  EXPECT_EQ(differing(s.mask, Scene::truth()), 0);
}

TEST(MaskEdges, WithoutAStepNothingChanges) {
  Scene s;
  s.depth.setTo(2.0f);  // a red picture on the wall: no depth step
  const cv::Mat before = s.mask.clone();
  refineMaskEdges(s.mask, s.depth, s.bgr, 2);
  EXPECT_EQ(differing(s.mask, before), 0);
  s.depth.setTo(0.f);  // no depth at all and one colour: nothing to go by
  s.bgr.setTo(cv::Scalar(90, 90, 90));
  refineMaskEdges(s.mask, s.depth, s.bgr, 2);
  EXPECT_EQ(differing(s.mask, before), 0);
  Scene off;
  refineMaskEdges(off.mask, off.depth, off.bgr, 0);  // radius 0: off
  EXPECT_EQ(differing(off.mask, before), 0);
}

TEST(MaskEdges, BadInputIsRefused) {
  Scene s;
  EXPECT_THROW(refineMaskEdges(s.mask, s.depth, s.bgr, -1), InputError);
  EXPECT_THROW(refineMaskEdges(s.mask, cv::Mat(20, 30, CV_32F, cv::Scalar(1.f)), s.bgr, 2), InputError);
  EXPECT_THROW(refineMaskEdges(s.mask, s.depth, cv::Mat(40, 60, CV_8UC1, cv::Scalar(0)), 2), InputError);
}

}  // namespace
}  // namespace ff
