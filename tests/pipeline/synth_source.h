#pragma once
// The pipeline tests' recording: a small synthetic scene (160x120 at 30 Hz) as a FrameSource,
// rendered frame by frame; throws at frame `fail_at` when set (a frame that fails mid-run).
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "flowfusion/core/error.h"
#include "flowfusion/io/frame_source.h"
#include "flowfusion/synth/synthetic_scene.h"

namespace ff::testing {

class SynthSource : public FrameSource {
 public:
  explicit SynthSource(int frames, int fail_at = -1) : fail_at_(fail_at) {
    synth::SynthConfig c;
    c.frames = frames;
    c.width = 160;
    c.height = 120;
    scene_ = std::make_unique<synth::SyntheticScene>(c);
  }
  const CameraIntrinsics& camera() const override { return scene_->camera(); }
  std::optional<RgbdFrame> next() override {
    if (next_ == scene_->frameCount()) return std::nullopt;
    if (next_ == fail_at_) throw InputError("frame " + std::to_string(next_) + ": unreadable");
    return scene_->render(next_++).frame;
  }
  std::optional<size_t> remaining() const override { return scene_->frameCount() - next_; }
  std::string name() const override { return "synth"; }
  // The colour timestamps of all frames, s.
  std::vector<double> stamps() const {
    std::vector<double> s;
    for (int i = 0; i < scene_->frameCount(); ++i) s.push_back(scene_->timestamp(i));
    return s;
  }

 private:
  std::unique_ptr<synth::SyntheticScene> scene_;
  int next_ = 0, fail_at_;
};

}  // namespace ff::testing
