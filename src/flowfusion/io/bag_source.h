#pragma once
// A ROS 1 or ROS 2 bag (io/bag_reader.h) as a frame source over a range of its associated frames:
// undistorted on reading when the camera has lens distortion (as TUM folders are), with the
// ground truth of options.bag.groundtruth (a TUM groundtruth.txt) when given.
#include <string>

#include "flowfusion/core/undistortion.h"
#include "flowfusion/io/bag_reader.h"
#include "flowfusion/io/frame_source.h"

namespace ff {

class BagSource : public FrameSource {
 public:
  // Throws InputError as BagReader::open does, on an unreadable ground truth, and when `range`
  // lies outside the associated frames.
  BagSource(const std::string& path, const SequenceOptions& options, FrameRange range = {});

  const CameraIntrinsics& camera() const override { return reader_.camera().intrinsics; }
  std::optional<RgbdFrame> next() override;
  std::optional<size_t> remaining() const override { return last_ + 1 - next_; }
  std::string name() const override { return reader_.path(); }
  cv::Mat toRawPixels(const cv::Mat& image) const override;
  const Trajectory* groundtruth() const override { return groundtruth_ ? &*groundtruth_ : nullptr; }
  const BagReader& reader() const { return reader_; }

 private:
  BagReader reader_;
  std::optional<Undistorter> undistorter_;
  std::optional<Trajectory> groundtruth_;
  size_t next_ = 0;
  size_t last_ = 0;
};

}  // namespace ff
