// The depth sensor's invalid band at the image's edges, per frame and over a run.
#include <gtest/gtest.h>

#include "flowfusion/core/sensor_band.h"

namespace ff {
namespace {

TEST(SensorBand, TakesTheEdgesLinesMostlyWithoutDepthUpToATenth) {
  cv::Mat depth(60, 80, CV_32F, cv::Scalar(2.f));
  depth(cv::Rect(68, 0, 12, 60)).setTo(0.f);  // the right 12 columns: a tenth is 8
  depth.row(0).setTo(0.f);
  depth(cv::Rect(0, 0, 1, 42)).setTo(0.f);  // the left column, 70 % without depth
  depth(cv::Rect(40, 0, 1, 60)).setTo(0.f);  // a column inside the view is no band
  const SensorBand widths = SensorBand::of(depth);
  EXPECT_EQ(widths.top, 1);
  EXPECT_EQ(widths.bottom, 0);
  EXPECT_EQ(widths.left, 1);
  EXPECT_EQ(widths.right, 8) << "a tenth of the width";
  const cv::Mat band = widths.pixels(depth.size());
  EXPECT_EQ(cv::countNonZero(band.col(0)), 60);
  EXPECT_EQ(cv::countNonZero(band.row(0)), 80);
  EXPECT_EQ(cv::countNonZero(band.col(72)), 60);
  EXPECT_EQ(cv::countNonZero(band(cv::Rect(68, 1, 4, 59))), 0) << "past a tenth of the width";
  EXPECT_EQ(cv::countNonZero(band(cv::Rect(40, 1, 1, 59))), 0);
}

TEST(SensorBandMedian, ARunsBandIsTheMedianSoThatANearFaceAtTheBorderIsNoBand) {
  cv::Mat depth(60, 80, CV_32F, cv::Scalar(2.f));
  depth(cv::Rect(76, 0, 4, 60)).setTo(0.f);  // the sensor's own band: 4 columns at the right
  cv::Mat near_face = depth.clone();
  near_face(cv::Rect(0, 5, 30, 55)).setTo(0.f);  // a face nearer than the range over the left border
  cv::Mat person = depth.clone();
  person(cv::Rect(76, 0, 4, 40)).setTo(1.5f);  // a mover in front of the band, with its depth
  const SensorBand widened = SensorBand::of(near_face);
  EXPECT_EQ(widened.left, 8) << "a tenth of the width, taken for band in that frame alone";
  EXPECT_EQ(SensorBand::of(person).right, 0);
  SensorBandMedian run;
  EXPECT_EQ(run.median().right, 0) << "no frame yet";
  for (int i = 0; i < 5; ++i) run.add(SensorBand::of(depth));
  for (int i = 0; i < 2; ++i) run.add(widened);
  for (int i = 0; i < 2; ++i) run.add(SensorBand::of(person));
  const SensorBand band = run.median();
  EXPECT_EQ(band.left, 0);
  EXPECT_EQ(band.right, 4);
  EXPECT_EQ(band.top, 0);
  EXPECT_EQ(band.bottom, 0);
  const cv::Mat pixels = band.pixels(depth.size());
  EXPECT_EQ(cv::countNonZero(pixels), 4 * 60);
  EXPECT_EQ(cv::countNonZero(pixels.colRange(76, 80)), 4 * 60);
}

}  // namespace
}  // namespace ff
