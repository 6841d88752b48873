#pragma once
// A TUM-layout folder (io/tum_sequence.h) as a frame source over a range of its frames.
#include "flowfusion/io/frame_source.h"
#include "flowfusion/io/tum_sequence.h"

namespace ff {

class TumFolderSource : public FrameSource {
 public:
  // Throws InputError when `range` lies outside the sequence.
  explicit TumFolderSource(TumSequence sequence, FrameRange range = {});

  const CameraIntrinsics& camera() const override { return sequence_.camera(); }
  std::optional<RgbdFrame> next() override;
  std::optional<size_t> remaining() const override { return last_ + 1 - next_; }
  std::string name() const override { return sequence_.dir(); }
  cv::Mat toRawPixels(const cv::Mat& image) const override;
  const Trajectory* groundtruth() const override;
  std::optional<std::string> masksDir() const override { return sequence_.masksDir(); }
  const TumSequence& sequence() const { return sequence_; }

 private:
  TumSequence sequence_;
  size_t next_ = 0;
  size_t last_ = 0;
};

}  // namespace ff
