#include <gtest/gtest.h>

#include "flowfusion/core/error.h"
#include "flowfusion/segmentation/map_agreement_mask.h"

namespace ff {
namespace {

// A 100 x 50 mask and its agreement at the segmentation level, half the size in each direction.
TEST(MapAgreementMask, ClearsExactlyThePixelsAgreeingAtTheSegmentationLevel) {
  cv::Mat mask(50, 100, CV_8U, cv::Scalar(0));
  mask(cv::Rect(20, 10, 40, 20)).setTo(255);  // a marked region of 800 pixels
  cv::Mat agreement(25, 50, CV_8U, cv::Scalar(0));
  agreement(cv::Rect(10, 5, 5, 10)).setTo(255);  // its left quarter: x 20-29, y 10-29 at full size
  agreement(cv::Rect(40, 20, 5, 5)).setTo(255);  // unmarked pixels stay unmarked
  clearMapAgreement(mask, agreement);
  EXPECT_EQ(cv::countNonZero(mask(cv::Rect(20, 10, 10, 20))), 0);
  EXPECT_EQ(cv::countNonZero(mask(cv::Rect(30, 10, 30, 20))), 600);
  EXPECT_EQ(cv::countNonZero(mask), 600);
}

TEST(MapAgreementMask, WithoutAMapTheMaskStaysAndBadInputIsRefused) {
  cv::Mat mask(50, 100, CV_8U, cv::Scalar(0));
  mask(cv::Rect(20, 10, 40, 20)).setTo(255);
  clearMapAgreement(mask, cv::Mat());
  EXPECT_EQ(cv::countNonZero(mask), 800);
  EXPECT_THROW(clearMapAgreement(mask, cv::Mat(25, 50, CV_32F, cv::Scalar(1))), InputError);
  cv::Mat wrong(50, 100, CV_32F, cv::Scalar(0));
  EXPECT_THROW(clearMapAgreement(wrong, cv::Mat(25, 50, CV_8U, cv::Scalar(255))), InputError);
  cv::Mat empty;
  EXPECT_THROW(clearMapAgreement(empty, cv::Mat()), InputError);
}

}  // namespace
}  // namespace ff
