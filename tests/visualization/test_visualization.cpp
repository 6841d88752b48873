#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "flowfusion/core/error.h"
#include "flowfusion/visualization/map_preview.h"
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

}  // namespace
}  // namespace ff
