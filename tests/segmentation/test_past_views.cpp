#include <gtest/gtest.h>

#include "flowfusion/core/error.h"
#include "flowfusion/segmentation/past_views.h"

namespace ff {
namespace {

// A 32x24 camera before a wall 4 m away (the world is the first view's camera frame).
const CameraIntrinsics kCamera{20, 20, 15.5, 11.5, 32, 24};
constexpr float kWallM = 4.f;

cv::Mat wall() { return cv::Mat(24, 32, CV_32F, cv::Scalar(kWallM)); }
cv::Mat everywhere() { return cv::Mat(24, 32, CV_8U, cv::Scalar(1)); }
SE3 movedAlongX(double x_m) {
  SE3 T = SE3::Identity();
  T.translation() = Eigen::Vector3d(x_m, 0, 0);
  return T;
}
PastSight at(const cv::Mat& sight, int u, int v) { return static_cast<PastSight>(sight.at<uint8_t>(v, u)); }

TEST(PastViews, TellsAStaticSurfaceSeenThereFromEmptySpaceSeenThrough) {
  PastViews views(kCamera, 1, 4);
  views.add(wall(), {}, SE3::Identity(), 0.0);
  // Seen 0.5 m to the side: the wall, and a box 2 m away over columns 10-13.
  cv::Mat depth = wall();
  depth.colRange(10, 14).setTo(2.f);
  const cv::Mat sight = views.sight(depth, movedAlongX(0.5), 1.0, 0.0, 0.03, everywhere());
  EXPECT_EQ(at(sight, 5, 12), PastSight::kStaticThere);  // the wall, where the first view saw it
  EXPECT_EQ(at(sight, 11, 12), PastSight::kSeenThrough);  // the first view saw the wall behind the box
}

TEST(PastViews, SeesNothingOutOfViewOnAMoverOrWhereNotAsked) {
  PastViews views(kCamera, 1, 4);
  cv::Mat scores(24, 32, CV_32F, cv::Scalar(0));
  scores.colRange(0, 8).setTo(1.f);  // a mover over the first view's left quarter
  views.add(wall(), scores, SE3::Identity(), 0.0);
  // 1.5 m to the right the view's right third lies beyond the first view (3.2 m half-width at 4 m).
  cv::Mat where = everywhere();
  where.at<uint8_t>(12, 16) = 0;
  const cv::Mat right = views.sight(wall(), movedAlongX(1.5), 1.0, 0.0, 0.03, where);
  EXPECT_EQ(at(right, 30, 12), PastSight::kNothing);      // out of the first view
  EXPECT_EQ(at(right, 16, 12), PastSight::kNothing);      // not asked
  EXPECT_EQ(at(right, 8, 12), PastSight::kStaticThere);   // the wall, in view of both
  const cv::Mat left = views.sight(wall(), movedAlongX(-0.2), 1.0, 0.0, 0.03, everywhere());
  EXPECT_EQ(at(left, 4, 12), PastSight::kNothing);        // the mover stood there
  EXPECT_EQ(at(left, 24, 12), PastSight::kStaticThere);
}

TEST(PastViews, KeepsOneFrameOfEveryNAndOnlyTheLatestViews) {
  const cv::Mat no_depth(24, 32, CV_32F, cv::Scalar(0));
  PastViews views(kCamera, 2, 1);
  EXPECT_TRUE(views.empty());
  views.add(wall(), {}, SE3::Identity(), 0.0);     // kept
  views.add(no_depth, {}, SE3::Identity(), 0.1);   // skipped (every 2nd)
  auto centre = [&] { return at(views.sight(wall(), SE3::Identity(), 1.0, 0.0, 0.03, everywhere()), 16, 12); };
  EXPECT_EQ(centre(), PastSight::kStaticThere);
  views.add(no_depth, {}, SE3::Identity(), 0.2);   // kept: replaces the wall
  EXPECT_EQ(centre(), PastSight::kNothing);
  PastViews off(kCamera, 1, 0);
  off.add(wall(), {}, SE3::Identity(), 0.0);
  EXPECT_TRUE(off.empty());
}

TEST(PastViews, AsksOnlyTheViewsAtLeastTheMinimumAgeOld) {
  PastViews views(kCamera, 1, 4);
  views.add(wall(), {}, SE3::Identity(), 0.0);
  const cv::Mat one_s_later = views.sight(wall(), SE3::Identity(), 1.0, 0.5, 0.03, everywhere());
  const cv::Mat too_soon = views.sight(wall(), SE3::Identity(), 1.0, 1.5, 0.03, everywhere());
  EXPECT_EQ(at(one_s_later, 16, 12), PastSight::kStaticThere);
  EXPECT_EQ(at(too_soon, 16, 12), PastSight::kNothing);
}

TEST(PastViews, WithholdsTheModelOcclusionOnlyWhereAStaticSurfaceWasSeen) {
  cv::Mat r_M(1, 3, CV_32F, cv::Scalar(0.5f));
  cv::Mat sight(1, 3, CV_8U);
  sight.at<uint8_t>(0, 0) = static_cast<uint8_t>(PastSight::kNothing);
  sight.at<uint8_t>(0, 1) = static_cast<uint8_t>(PastSight::kStaticThere);
  sight.at<uint8_t>(0, 2) = static_cast<uint8_t>(PastSight::kSeenThrough);
  const cv::Mat out = PastViews::withoutStaticThere(r_M, sight);
  EXPECT_FLOAT_EQ(out.at<float>(0, 0), 0.5f);
  EXPECT_FLOAT_EQ(out.at<float>(0, 1), 0.f);
  EXPECT_FLOAT_EQ(out.at<float>(0, 2), 0.5f);
  EXPECT_FLOAT_EQ(r_M.at<float>(0, 1), 0.5f);  // the input is left as it was
}

TEST(PastViews, RejectsBadSettingsAndImages) {
  EXPECT_THROW(PastViews(kCamera, 0, 4), InputError);
  EXPECT_THROW(PastViews(kCamera, 1, -1), InputError);
  PastViews views(kCamera, 1, 4);
  EXPECT_THROW(views.add(cv::Mat(10, 10, CV_32F, cv::Scalar(1)), {}, SE3::Identity(), 0.0), InputError);
  EXPECT_THROW(views.add(wall(), cv::Mat(24, 32, CV_8U, cv::Scalar(0)), SE3::Identity(), 0.0), InputError);
  EXPECT_THROW(views.sight(wall(), SE3::Identity(), 0.0, 0.0, 0.03, cv::Mat(24, 32, CV_32F)), InputError);
}

}  // namespace
}  // namespace ff
