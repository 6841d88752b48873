#include <gtest/gtest.h>

#include "flowfusion/core/error.h"
#include "flowfusion/segmentation/small_regions.h"

namespace ff {
namespace {

// A 100 x 50 image (5000 pixels): at a share of 0.02, regions of fewer than 100 pixels are small.
cv::Mat emptyMask() { return cv::Mat(50, 100, CV_8U, cv::Scalar(0)); }

int marked(const cv::Mat& mask, const cv::Rect& r) { return cv::countNonZero(mask(r)); }

TEST(SmallRegions, ASmallRegionInsideTheViewIsDroppedALargeOneKept) {
  cv::Mat mask = emptyMask();
  mask(cv::Rect(10, 10, 9, 11)).setTo(255);  // 99 pixels
  mask(cv::Rect(40, 10, 10, 10)).setTo(255);  // 100 pixels
  mask(cv::Rect(70, 10, 5, 5)).setTo(255);   // 25 pixels, and 75 touching its corner
  mask(cv::Rect(75, 15, 15, 5)).setTo(128);  // diagonally: one 8-connected region of 100
  dropSmallInteriorRegions(mask, 0.02);
  EXPECT_EQ(marked(mask, cv::Rect(10, 10, 9, 11)), 0);
  EXPECT_EQ(marked(mask, cv::Rect(40, 10, 10, 10)), 100);
  EXPECT_EQ(cv::countNonZero(mask), 200);
}

TEST(SmallRegions, ASliceAtAnyBorderOfTheImageIsKept) {
  cv::Mat mask = emptyMask();
  mask(cv::Rect(0, 20, 3, 10)).setTo(255);   // left
  mask(cv::Rect(97, 20, 3, 10)).setTo(255);  // right
  mask(cv::Rect(40, 0, 10, 2)).setTo(255);   // top
  mask(cv::Rect(40, 48, 10, 2)).setTo(255);  // bottom
  mask(cv::Rect(1, 40, 3, 3)).setTo(255);    // one pixel off the border: dropped
  dropSmallInteriorRegions(mask, 0.02);
  EXPECT_EQ(cv::countNonZero(mask), 30 + 30 + 20 + 20);
  EXPECT_EQ(marked(mask, cv::Rect(1, 40, 3, 3)), 0);
}

TEST(SmallRegions, ShareZeroKeepsEverythingAndBadInputIsRefused) {
  cv::Mat mask = emptyMask();
  mask.at<uchar>(25, 50) = 255;
  dropSmallInteriorRegions(mask, 0);
  EXPECT_EQ(cv::countNonZero(mask), 1);
  EXPECT_THROW(dropSmallInteriorRegions(mask, 1.0), InputError);
  EXPECT_THROW(dropSmallInteriorRegions(mask, -0.1), InputError);
  cv::Mat wrong(50, 100, CV_32F, cv::Scalar(0));
  EXPECT_THROW(dropSmallInteriorRegions(wrong, 0.02), InputError);
  cv::Mat empty;
  EXPECT_THROW(dropSmallInteriorRegions(empty, 0.02), InputError);
}

}  // namespace
}  // namespace ff
