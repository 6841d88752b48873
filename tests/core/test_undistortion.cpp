#include <gtest/gtest.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "flowfusion/core/camera.h"
#include "flowfusion/core/error.h"
#include "flowfusion/core/undistortion.h"

namespace ff {
namespace {

// Where a lens with `d` images the camera-frame point p (OpenCV's model), pixels.
cv::Point2d distortedPixel(const CameraIntrinsics& c, const LensDistortion& d, const Eigen::Vector3d& p) {
  const cv::Mat K = (cv::Mat_<double>(3, 3) << c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1);
  const cv::Mat D = (cv::Mat_<double>(1, 5) << d.k1, d.k2, d.p1, d.p2, d.k3);
  std::vector<cv::Point3d> in{{p.x(), p.y(), p.z()}};
  std::vector<cv::Point2d> out;
  cv::projectPoints(in, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K, D, out);
  return out[0];
}

// Points spread over the view, corners included, where fr1's lens moves them most.
std::vector<Eigen::Vector3d> viewPoints(const CameraIntrinsics& c) {
  std::vector<Eigen::Vector3d> pts;
  for (double u : {30.0, 160.0, 320.0, 480.0, 610.0})
    for (double v : {30.0, 120.0, 240.0, 360.0, 450.0}) pts.push_back(c.backproject(u, v, 2.0));
  return pts;
}

TEST(Undistortion, DepthLandsWhereThePinholeModelProjects) {
  const CameraIntrinsics cam = *freiburgPreset(1);
  const LensDistortion lens = *freiburgDistortion(1);
  const Undistorter undistorter(cam, lens);
  double largest_shift = 0;
  for (const Eigen::Vector3d& p : viewPoints(cam)) {
    // A raw depth image with one 3x3 patch where the lens put the point.
    const cv::Point2d raw = distortedPixel(cam, lens, p);
    cv::Mat depth(cam.height, cam.width, CV_16UC1, cv::Scalar(0));
    const cv::Rect patch(static_cast<int>(std::lround(raw.x)) - 1, static_cast<int>(std::lround(raw.y)) - 1, 3, 3);
    depth(patch & cv::Rect(0, 0, cam.width, cam.height)).setTo(1234);
    const Eigen::Vector2d pinhole = cam.project(p);
    largest_shift = std::max(largest_shift, std::hypot(raw.x - pinhole.x(), raw.y - pinhole.y()));
    const cv::Mat out = undistorter.undistortDepth(depth);
    // The patch, undistorted, covers the pinhole projection (within a pixel of its centre).
    const int u = static_cast<int>(std::lround(pinhole.x())), v = static_cast<int>(std::lround(pinhole.y()));
    EXPECT_EQ(out.at<uint16_t>(v, u), 1234) << "point at pinhole pixel (" << u << ", " << v << ")";
    EXPECT_EQ(cv::countNonZero((out != 0) & (out != 1234)), 0) << "nearest sampling never mixes depths";
  }
  // fr1's lens matters: several pixels at the corners.
  EXPECT_GT(largest_shift, 5.0);
}

TEST(Undistortion, MasksGoBackToRawPixels) {
  const CameraIntrinsics cam = *freiburgPreset(1);
  const LensDistortion lens = *freiburgDistortion(1);
  const Undistorter undistorter(cam, lens);
  for (const Eigen::Vector3d& p : viewPoints(cam)) {
    const Eigen::Vector2d pinhole = cam.project(p);
    cv::Mat mask(cam.height, cam.width, CV_8U, cv::Scalar(0));
    cv::circle(mask, cv::Point(static_cast<int>(std::lround(pinhole.x())), static_cast<int>(std::lround(pinhole.y()))),
               3, cv::Scalar(255), cv::FILLED);
    const cv::Mat raw = undistorter.toRawPixels(mask);
    const cv::Point2d expected = distortedPixel(cam, lens, p);
    const int u = static_cast<int>(std::lround(expected.x)), v = static_cast<int>(std::lround(expected.y));
    EXPECT_EQ(raw.at<uint8_t>(v, u), 255) << "mask blob at raw pixel (" << u << ", " << v << ")";
  }
}

TEST(Undistortion, ColourKeepsItsValues) {
  const CameraIntrinsics cam = *freiburgPreset(1);
  const Undistorter undistorter(cam, *freiburgDistortion(1));
  const cv::Mat grey(cam.height, cam.width, CV_8UC3, cv::Scalar(40, 90, 200));
  const cv::Mat out = undistorter.undistortColor(grey);
  ASSERT_EQ(out.type(), CV_8UC3);
  // Interpolation and the border keep a uniform colour everywhere, the rim included.
  cv::Mat same;
  cv::inRange(out, cv::Scalar(40, 90, 200), cv::Scalar(40, 90, 200), same);
  EXPECT_EQ(cv::countNonZero(same), cam.width * cam.height);
}

TEST(Camera, DistortionInSpecs) {
  const CameraModel fr1 = parseCameraModel("fr1");
  EXPECT_DOUBLE_EQ(fr1.distortion.k1, 0.2624);
  EXPECT_DOUBLE_EQ(fr1.distortion.k3, 1.1633);
  EXPECT_TRUE(parseCameraModel("fr3").distortion.none());
  EXPECT_TRUE(parseCameraModel("500,501,320,240").distortion.none());
  const CameraModel m = parseCameraModel("500,501,320,240,640,480,0.1,-0.2,0.001,0.002,0.3");
  EXPECT_DOUBLE_EQ(m.distortion.k2, -0.2);
  EXPECT_DOUBLE_EQ(m.distortion.p2, 0.002);
  EXPECT_FALSE(m.distortion.none());
  EXPECT_THROW(parseCameraModel("500,501,320,240,640,480,0.1"), InputError);
  EXPECT_THROW(parseCameraModel("500,501,320,240,640,480,nan,0,0,0,0"), InputError);
}

}  // namespace
}  // namespace ff
