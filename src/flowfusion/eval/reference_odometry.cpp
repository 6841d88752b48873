#include "flowfusion/eval/reference_odometry.h"

#include <chrono>
#include <opencv2/core/eigen.hpp>
#include <opencv2/rgbd.hpp>

#include "flowfusion/core/error.h"
#include "flowfusion/core/timings.h"
#include "flowfusion/eval/bench_utils.h"
#include "flowfusion/io/tum_sequence.h"

namespace ff::eval {

struct ReferenceOdometry::Impl {
  cv::Ptr<cv::rgbd::Odometry> odometry;
  cv::Ptr<cv::rgbd::OdometryFrame> previous;
};

std::string methodName(ReferenceMethod method) {
  return method == ReferenceMethod::RgbdOdometry ? "opencv-RgbdOdometry" : "opencv-RgbdICPOdometry";
}

ReferenceOdometry::ReferenceOdometry(ReferenceMethod method, const CameraIntrinsics& camera, const SE3& T_world_first)
    : impl_(std::make_unique<Impl>()), method_(method), camera_(camera), T_world_first_(T_world_first) {
  if (!camera.valid()) throw InputError("reference odometry: camera intrinsics are not valid");
  cv::Mat K;
  cv::eigen2cv(camera.K(), K);
  K.convertTo(K, CV_32F);
  if (method == ReferenceMethod::RgbdOdometry)
    impl_->odometry = cv::rgbd::RgbdOdometry::create(K);
  else
    impl_->odometry = cv::rgbd::RgbdICPOdometry::create(K);
}

ReferenceOdometry::~ReferenceOdometry() = default;

SE3 ReferenceOdometry::track(const RgbdFrame& frame) {
  if (frame.width() != camera_.width || frame.height() != camera_.height || frame.intensity.size() != frame.depth.size())
    throw InputError(frame.name + ": frame is " + std::to_string(frame.width()) + "x" +
                     std::to_string(frame.height()) + ", the camera " + std::to_string(camera_.width) + "x" +
                     std::to_string(camera_.height));
  cv::Mat grey;
  frame.intensity.convertTo(grey, CV_8U, 255.0);
  const cv::Mat mask = frame.depth > 0;
  auto current = cv::rgbd::OdometryFrame::create(grey, frame.depth, mask);

  if (!impl_->previous) {
    impl_->previous = current;
    trajectory_.push_back({frame.timestamp, T_world_first_});
    return T_world_first_;
  }
  cv::Mat Rt;
  const auto start = std::chrono::steady_clock::now();
  // Rt maps points of the source (previous) frame into the destination (current) one.
  const bool ok = impl_->odometry->compute(impl_->previous, current, Rt);
  call_ms_.push_back(msSince(start));
  if (ok) {
    Eigen::Matrix4d T_cur_prev;
    cv::cv2eigen(Rt, T_cur_prev);
    T_prev_cur_ = SE3(T_cur_prev).inverse();
  } else {
    ++failures_;
  }
  const SE3 T_world_cur = trajectory_.back().T_world_cam * T_prev_cur_;
  trajectory_.push_back({frame.timestamp, T_world_cur});
  impl_->previous = current;
  return T_world_cur;
}

double ReferenceOdometry::medianMs() const { return median(call_ms_); }

ReferenceRun runReferenceOdometry(ReferenceMethod method, const TumSequence& sequence,
                                  std::optional<size_t> max_frames) {
  const size_t n = std::min(sequence.size(), max_frames.value_or(sequence.size()));
  if (n == 0) throw InputError(sequence.dir() + ": no frames to run the reference odometry on");
  const RgbdFrame first = sequence.load(0);
  SE3 T_world_first = SE3::Identity();
  if (sequence.groundtruth()) interpolatePose(*sequence.groundtruth(), first.timestamp, T_world_first);
  ReferenceOdometry odometry(method, sequence.camera(), T_world_first);
  odometry.track(first);
  for (size_t i = 1; i < n; ++i) odometry.track(sequence.load(i));
  return {odometry.trajectory(), odometry.failures(), odometry.medianMs()};
}

}  // namespace ff::eval
