#pragma once
// Dense optical flow from frame A to frame B (the paper uses PWC-Net on a GPU; we use CPU methods
// from OpenCV, docs/design.md).
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "flowfusion/core/config_enum.h"

namespace ff {

// Pixel x of A moves to x + uv(x) in B. CV_32FC2, pixels, same size as the input images.
struct FlowField {
  cv::Mat uv;
};

enum class FlowBackend { Dis, Farneback };
FLOWFUSION_CONFIG_ENUM(FlowBackend, "flow.backend", {FlowBackend::Dis, "dis"}, {FlowBackend::Farneback, "farneback"})
enum class DisPreset { Ultrafast, Fast, Medium };
FLOWFUSION_CONFIG_ENUM(DisPreset, "flow.dis_preset", {DisPreset::Ultrafast, "ultrafast"}, {DisPreset::Fast, "fast"},
                       {DisPreset::Medium, "medium"})

struct FlowConfig {
  // dis: cv::DISOpticalFlow; farneback: cv::FarnebackOpticalFlow, slower and less accurate on our
  // frames, kept for comparison (docs/tuning.md#flow).
  FlowBackend backend = FlowBackend::Dis;
  // OpenCV's DIS presets (patch size, stride, pyramid depth, refinement iterations); medium: its
  // finer flow separates movers on real frames (docs/tuning.md#flow).
  DisPreset dis_preset = DisPreset::Medium;
  // Flow is computed on the images downsampled by this factor (1, 2 or 4) and upsampled
  // bilinearly with the vectors scaled back.
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

// Throws InputError naming the first bad setting.
void validate(const FlowConfig& config);

// The backend the configuration names (Basalt's OpticalFlowFactory); throws InputError on a bad
// configuration.
std::unique_ptr<OpticalFlow> makeOpticalFlow(const FlowConfig& config);

// Resamples a flow field to `size` (bilinear), scaling the vectors by the size ratio.
FlowField resizeFlow(const FlowField& flow, cv::Size size);

}  // namespace ff
