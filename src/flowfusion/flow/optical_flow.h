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
  // "dis" (cv::DISOpticalFlow) or "farneback" (cv::FarnebackOpticalFlow, for comparison:
  // slower and less accurate on our synthetic frames, see bench/bench_flow_segmentation.cpp).
  std::string backend = "dis";
  // DIS preset: "ultrafast", "fast" or "medium" (OpenCV's presets: patch size, stride,
  // pyramid depth, refinement iterations).
  std::string dis_preset = "fast";
  // Flow is computed on the images downsampled by this factor (1, 2 or 4) and upsampled
  // bilinearly with the vectors scaled back. 2 halves the cost for ~0.1 px more end-point
  // error on 640x480 frames (measured, see the benchmark); it also widens DIS's capture range.
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
