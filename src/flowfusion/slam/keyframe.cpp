#include "flowfusion/slam/keyframe.h"

#include <opencv2/imgproc.hpp>

namespace ff {

namespace {
constexpr double kDepthUnitsPerM = 5000.0;  // as TUM's depth PNGs
}  // namespace

std::shared_ptr<const KeyframeImages> makeKeyframeImages(const RgbdFrame& frame, const CameraIntrinsics& camera,
                                                         const cv::Mat& scores, const SlamConfig& config) {
  auto k = std::make_shared<KeyframeImages>();
  k->camera = camera.atLevel(config.keyframe_level);
  const cv::Size size(k->camera.width, k->camera.height);
  cv::Mat intensity, depth, weight;
  cv::resize(frame.intensity, intensity, size, 0, 0, cv::INTER_AREA);
  intensity.convertTo(k->intensity, CV_8U, 255.0);
  cv::resize(frame.depth, depth, size, 0, 0, cv::INTER_NEAREST);  // no depth mixed across edges
  depth.convertTo(k->depth, CV_16U, kDepthUnitsPerM);
  if (scores.empty()) {
    weight = cv::Mat(size, CV_32F, cv::Scalar(1.0f));
  } else {
    cv::resize(scores, weight, size, 0, 0, cv::INTER_NEAREST);
    weight = 1.0f - weight;
  }
  weight.convertTo(k->static_weight, CV_8U, 255.0);

  const int small_w = config.fern_image_width;
  const cv::Size small(small_w, std::max(1, small_w * camera.height / camera.width));
  cv::Mat bgr;
  cv::resize(frame.color, bgr, small, 0, 0, cv::INTER_AREA);
  cv::GaussianBlur(bgr, k->small_bgr, cv::Size(5, 5), 0);
  cv::Mat small_weight;
  cv::resize(depth, k->small_depth, small, 0, 0, cv::INTER_NEAREST);
  cv::resize(weight, small_weight, small, 0, 0, cv::INTER_AREA);  // a pixel mixed with a mover counts as one
  k->small_depth.setTo(0.0f, small_weight < 0.5f);
  return k;
}

OdometryFrame KeyframeImages::odometryFrame(const OdometryConfig& config) const {
  cv::Mat i, d;
  intensity.convertTo(i, CV_32F, 1.0 / 255.0);
  depth.convertTo(d, CV_32F, 1.0 / kDepthUnitsPerM);
  return prepareOdometryFrame(i, d, camera, config);
}

cv::Mat KeyframeImages::staticWeights() const {
  cv::Mat w;
  static_weight.convertTo(w, CV_32F, 1.0 / 255.0);
  return w;
}

}  // namespace ff
