#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "flowfusion/core/error.h"
#include "flowfusion/visualization/map_preview.h"
#include "flowfusion/visualization/mask_sheet.h"
#include "flowfusion/visualization/overlay.h"
#include "fusion/room_fixture.h"
#include "testing/test_util.h"

namespace ff {
namespace {

using testing::RoomFixture;

TEST(Visualization, PreviewsAndMaskOverlay) {
  RoomFixture room;
  room.frames = 10;
  StaticMap map;
  for (int i = 0; i < room.frames; ++i) map.integrate(room.render(i).frame, room.camera, room.pose(i));
  testing::TempDir dir;
  const auto paths = writePreviews(map, dir.str());
  ASSERT_GE(paths.size(), 3u);
  for (const auto& p : paths) {
    const cv::Mat img = cv::imread(p);
    ASSERT_FALSE(img.empty()) << p;
    cv::Mat grey;
    cv::cvtColor(img, grey, cv::COLOR_BGR2GRAY);
    EXPECT_GT(cv::countNonZero(grey), img.total() / 4) << p;
  }

  const cv::Mat bgr(4, 4, CV_8UC3, cv::Scalar(100, 100, 100));
  cv::Mat mask = cv::Mat::zeros(4, 4, CV_8UC1);
  mask.at<uchar>(1, 2) = 255;
  const cv::Mat out = overlayMask(bgr, mask);
  EXPECT_EQ(out.at<cv::Vec3b>(0, 0), cv::Vec3b(100, 100, 100));
  const cv::Vec3b tinted = out.at<cv::Vec3b>(1, 2);
  EXPECT_GT(tinted[2], 150);
  EXPECT_LT(tinted[0], 60);
  EXPECT_THROW(overlayMask(bgr, cv::Mat::zeros(3, 3, CV_8UC1)), InputError);
}

TEST(Visualization, MaskComparisonColoursAndContactSheetLayout) {
  const cv::Mat bgr(48, 64, CV_8UC3, cv::Scalar(100, 100, 100));
  cv::Mat gt = cv::Mat::zeros(48, 64, CV_8UC1), est = cv::Mat::zeros(48, 64, CV_8UC1);
  gt(cv::Rect(0, 0, 20, 48)).setTo(255);   // columns 0-19 truly dynamic
  est(cv::Rect(10, 0, 20, 48)).setTo(255);  // columns 10-29 estimated dynamic
  const cv::Mat cmp = maskComparison(bgr, gt, est);
  EXPECT_EQ(cmp.at<cv::Vec3b>(5, 5), cv::Vec3b(0, 0, 255));    // missed: red
  EXPECT_EQ(cmp.at<cv::Vec3b>(5, 15), cv::Vec3b(0, 200, 0));   // hit: green
  EXPECT_EQ(cmp.at<cv::Vec3b>(5, 25), cv::Vec3b(255, 64, 0));  // false: blue
  EXPECT_EQ(cmp.at<cv::Vec3b>(5, 40), cv::Vec3b(50, 50, 50));  // static and so estimated: dimmed

  cv::Mat depth(48, 64, CV_32FC1, cv::Scalar(2.0f));
  depth(cv::Rect(0, 0, 8, 8)).setTo(0.0f);
  const cv::Mat coloured = depthColormap(depth, 4.0);
  EXPECT_EQ(coloured.at<cv::Vec3b>(2, 2), cv::Vec3b(0, 0, 0));  // no measurement: black
  EXPECT_NE(coloured.at<cv::Vec3b>(20, 20), cv::Vec3b(0, 0, 0));

  // A title strip, then one row per frame of five columns, each 64 px wide here (48 px high).
  const std::vector<MaskSheetRow> rows(3, MaskSheetRow{bgr, depth, gt, est, "1.000 s\nIoU 0.33"});
  const cv::Mat sheet = maskContactSheet(rows, 64);
  EXPECT_EQ(sheet.cols, 5 * 64);
  EXPECT_GT(sheet.rows, 3 * 48);
  EXPECT_LT(sheet.rows, 3 * 48 + 48);
  // The comparison column of the last row, away from the label: the same colours.
  const int row_top = sheet.rows - 48;
  EXPECT_EQ(sheet.at<cv::Vec3b>(row_top + 30, 4 * 64 + 5), cv::Vec3b(0, 0, 255));
  EXPECT_EQ(sheet.at<cv::Vec3b>(row_top + 30, 4 * 64 + 25), cv::Vec3b(255, 64, 0));

  EXPECT_THROW(maskContactSheet({}), InputError);
  std::vector<MaskSheetRow> bad = rows;
  bad[1].est_mask = cv::Mat::zeros(10, 10, CV_8UC1);
  EXPECT_NE(testing::inputErrorOf([&] { maskContactSheet(bad, 64); }).find("row 1"), std::string::npos);
}

}  // namespace
}  // namespace ff
