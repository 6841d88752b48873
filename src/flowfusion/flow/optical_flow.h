#pragma once
// Dense optical flow from frame A to frame B (NOTES.md step 3; the paper uses PWC-Net on a GPU,
// we use CPU methods from OpenCV).
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace ff {

// Pixel x of A moves to x + uv(x) in B. CV_32FC2, pixels, same size as the input images.
struct FlowField {
  cv::Mat uv;
};

struct FlowConfig {
  // "dis" (cv::DISOpticalFlow) or "farneback" (cv::FarnebackOpticalFlow, for comparison: on
  // our synthetic 640x480 frames 1.2 px mean end-point error in 28 ms CPU at downscale 2,
  // against DIS "fast" 0.34 px in 2.4 ms; bench/bench_flow_segmentation.cpp).
  std::string backend = "dis";
  // DIS preset: "ultrafast", "fast" or "medium" (OpenCV's presets: patch size, stride,
  // pyramid depth, refinement iterations). At 640x480, downscale 2, measured mean EPE / CPU
  // time: ultrafast 0.41 px / 1.5 ms, fast 0.34 px / 2.4 ms, medium 0.17 px / 8.1 ms.
  std::string dis_preset = "fast";
  // Flow is computed on the images downsampled by this factor (1, 2 or 4) and upsampled
  // bilinearly with the vectors scaled back. For DIS "fast" at 640x480: 1 -> 0.20 px in 6.0 ms,
  // 2 -> 0.34 px in 2.4 ms, 4 -> 1.0 px in 1.2 ms. A 0.15 px error is far below the flow
  // residual of moving objects (several px), so 2 is the default within the 33 ms budget.
  int downscale = 2;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(FlowConfig, backend, dis_preset, downscale)

class OpticalFlow {
 public:
  virtual ~OpticalFlow() = default;
  // Both images CV_32FC1 in [0, 1] (RgbdFrame::intensity), same size. Throws InputError on
  // empty, mismatched or wrongly typed images.
  virtual FlowField compute(const cv::Mat& intensity_a, const cv::Mat& intensity_b) = 0;
  virtual std::string name() const = 0;
};

// Throws InputError for an unknown backend or preset name or a bad downscale, listing the
// valid choices.
std::unique_ptr<OpticalFlow> makeOpticalFlow(const FlowConfig& config);
std::vector<std::string> opticalFlowBackends();

// Resamples a flow field to `size` (bilinear), scaling the vectors by the size ratio.
FlowField resizeFlow(const FlowField& flow, cv::Size size);

}  // namespace ff
