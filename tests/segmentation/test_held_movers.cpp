#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "flowfusion/segmentation/held_movers.h"

namespace ff {
namespace {

// An 80 x 60 view of a wall 3 m away with a person-sized patch 1.5 m away (columns 30-39, rows
// 20-39) that the scores saw moving clearly in the frame at t = 0.
struct View {
  CameraIntrinsics camera{60, 60, 40, 30, 80, 60};
  cv::Mat disagrees = cv::Mat(60, 80, CV_32F, cv::Scalar(0.f));  // a_M: compared with the map, not on it
  cv::Mat wall = cv::Mat(60, 80, CV_32F, cv::Scalar(3.f));
  cv::Mat with_person = wall.clone();
  cv::Mat seen = cv::Mat(60, 80, CV_8U, cv::Scalar(0));
  cv::Rect person{30, 20, 10, 20};
  View() {
    with_person(person).setTo(1.5f);
    seen(person).setTo(255);
  }
};

constexpr double kDt = 1.0 / 30;

TEST(HeldMovers, AMoverSeenMovingIsHeldWhereItStandsDecayingOverTheHoldTime) {
  const View v;
  HeldMovers held(1.0);
  held.remember({}, v.seen, 0.0);
  // The person stands still: the hold is there, at exp(-dt / 1 s), and nowhere else.
  cv::Mat hold = held.carried(v.with_person, 0.0, v.camera, SE3::Identity(), v.with_person, kDt, v.disagrees);
  ASSERT_FALSE(hold.empty());
  EXPECT_NEAR(hold.at<float>(30, 35), std::exp(-kDt), 1e-5);
  EXPECT_EQ(cv::countNonZero(hold), v.person.area());
  // Frame after frame without being seen moving again: below 0.5 after ln 2 of the hold time.
  double t = kDt;
  int frames_held = 1;
  while (hold.at<float>(30, 35) > 0.5f) {
    held.remember(hold, cv::Mat(60, 80, CV_8U, cv::Scalar(0)), t);
    hold = held.carried(v.with_person, t, v.camera, SE3::Identity(), v.with_person, t + kDt, v.disagrees);
    t += kDt;
    ++frames_held;
  }
  EXPECT_EQ(frames_held, static_cast<int>(std::ceil(std::log(2.0) / kDt)));
}

TEST(HeldMovers, TheHoldFollowsTheCameraAndLetsGoWhereTheMoverLeftOrTheMapDoesNotDisagree) {
  const View v;
  HeldMovers held(1.0);
  held.remember({}, v.seen, 0.0);
  // The camera moves 5 cm to the left (x): a point 1.5 m away moves 60 * 0.05 / 1.5 = 2 px right.
  SE3 T_prev_cur = SE3::Identity();
  T_prev_cur.translation() = Eigen::Vector3d(-0.05, 0, 0);
  cv::Mat moved_person = v.wall.clone();
  moved_person(v.person + cv::Point(2, 0)).setTo(1.5f);
  const cv::Mat hold = held.carried(v.with_person, 0.0, v.camera, T_prev_cur, moved_person, kDt, v.disagrees);
  EXPECT_GT(hold.at<float>(30, 41), 0.9f);
  EXPECT_EQ(hold.at<float>(30, 31), 0.f);
  // The person walked on: where the wall shows again, nothing is held.
  const cv::Mat left = held.carried(v.with_person, 0.0, v.camera, SE3::Identity(), v.wall, kDt, v.disagrees);
  EXPECT_EQ(cv::countNonZero(left), 0);
  // Held only where the pixel was compared with the stable map and is not on it: not where it agrees
  // (rows 20-29), not where the map has nothing to compare with (NaN, rows 30-34).
  cv::Mat agreement = v.disagrees.clone();
  agreement(cv::Rect(30, 20, 10, 10)).setTo(1.f);
  agreement(cv::Rect(30, 30, 10, 5)).setTo(std::numeric_limits<float>::quiet_NaN());
  const cv::Mat part = held.carried(v.with_person, 0.0, v.camera, SE3::Identity(), v.with_person, kDt, agreement);
  EXPECT_EQ(cv::countNonZero(part), v.person.area() / 4);
  EXPECT_GT(part.at<float>(37, 35), 0.9f);
  // Without a map, nothing is held.
  EXPECT_TRUE(held.carried(v.with_person, 0.0, v.camera, SE3::Identity(), v.with_person, kDt, {}).empty());
}

TEST(HeldMovers, NothingIsCarriedPastAFrameNotRememberedOrWhenOff) {
  const View v;
  HeldMovers held(1.0);
  held.remember({}, v.seen, 0.0);
  // The previous frame is not the one remembered (a frame scored nothing in between).
  EXPECT_TRUE(
      held.carried(v.with_person, kDt, v.camera, SE3::Identity(), v.with_person, 2 * kDt, v.disagrees).empty());
  HeldMovers off(0.0);
  EXPECT_FALSE(off.enabled());
  off.remember({}, v.seen, 0.0);
  EXPECT_TRUE(off.carried(v.with_person, 0.0, v.camera, SE3::Identity(), v.with_person, kDt, v.disagrees).empty());
}

}  // namespace
}  // namespace ff
