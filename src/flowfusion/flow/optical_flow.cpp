#include "flowfusion/flow/optical_flow.h"

#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <opencv2/video/tracking.hpp>

#include "flowfusion/core/error.h"

namespace ff {

namespace {

void checkInputs(const cv::Mat& a, const cv::Mat& b, const std::string& who) {
  if (a.empty() || b.empty()) throw InputError(who + ": empty input image");
  if (a.type() != CV_32FC1 || b.type() != CV_32FC1)
    throw InputError(who + ": expected CV_32FC1 intensity images in [0, 1]");
  if (a.size() != b.size()) throw InputError(who + ": images A and B differ in size");
}

cv::Mat toGrey8(const cv::Mat& intensity, int downscale) {
  cv::Mat small = intensity;
  if (downscale > 1) cv::resize(intensity, small, intensity.size() / downscale, 0, 0, cv::INTER_AREA);
  cv::Mat grey;
  small.convertTo(grey, CV_8U, 255.0);
  return grey;
}

// Shared by the backends: conversion to 8-bit, optional downscaling, and the way back.
class OpenCvFlow : public OpticalFlow {
 public:
  OpenCvFlow(cv::Ptr<cv::DenseOpticalFlow> impl, std::string name, int downscale)
      : impl_(std::move(impl)), name_(std::move(name)), downscale_(downscale) {}

  FlowField compute(const cv::Mat& intensity_a, const cv::Mat& intensity_b) override {
    checkInputs(intensity_a, intensity_b, name_);
    if (intensity_a.cols / downscale_ < 16 || intensity_a.rows / downscale_ < 16)
      throw InputError(name_ + ": images too small for flow at downscale " + std::to_string(downscale_));
    FlowField f;
    impl_->calc(toGrey8(intensity_a, downscale_), toGrey8(intensity_b, downscale_), f.uv);
    if (downscale_ > 1) f = resizeFlow(f, intensity_a.size());
    return f;
  }
  std::string name() const override { return name_; }

 private:
  cv::Ptr<cv::DenseOpticalFlow> impl_;
  std::string name_;
  int downscale_;
};

}  // namespace

void validate(const FlowConfig& config) {
  if (config.downscale != 1 && config.downscale != 2 && config.downscale != 4)
    throw InputError("flow.downscale must be 1, 2 or 4, got " + std::to_string(config.downscale));
}

std::unique_ptr<OpticalFlow> makeOpticalFlow(const FlowConfig& config) {
  validate(config);
  switch (config.backend) {
    case FlowBackend::Dis: {
      const int preset = config.dis_preset == DisPreset::Ultrafast ? cv::DISOpticalFlow::PRESET_ULTRAFAST
                         : config.dis_preset == DisPreset::Fast    ? cv::DISOpticalFlow::PRESET_FAST
                                                                   : cv::DISOpticalFlow::PRESET_MEDIUM;
      return std::make_unique<OpenCvFlow>(cv::DISOpticalFlow::create(preset), "dis-" + enumName(config.dis_preset),
                                          config.downscale);
    }
    case FlowBackend::Farneback:
      return std::make_unique<OpenCvFlow>(cv::FarnebackOpticalFlow::create(), "farneback", config.downscale);
  }
  throw std::logic_error("makeOpticalFlow: unhandled flow.backend");
}

FlowField resizeFlow(const FlowField& flow, cv::Size size) {
  if (flow.uv.size() == size) return flow;
  FlowField out;
  cv::resize(flow.uv, out.uv, size, 0, 0, cv::INTER_LINEAR);
  const double sx = static_cast<double>(size.width) / flow.uv.cols;
  const double sy = static_cast<double>(size.height) / flow.uv.rows;
  cv::multiply(out.uv, cv::Scalar(sx, sy), out.uv);
  return out;
}

}  // namespace ff
