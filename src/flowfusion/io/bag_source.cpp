#include "flowfusion/io/bag_source.h"

#include "flowfusion/core/error.h"

namespace ff {

BagSource::BagSource(const std::string& path, const SequenceOptions& options, FrameRange range)
    : reader_(BagReader::open(path, options)) {
  const size_t n = reader_.size();
  next_ = static_cast<size_t>(range.first);
  last_ = range.last < 0 ? n - 1 : static_cast<size_t>(range.last);
  if (next_ >= n || last_ >= n)
    throw InputError(path + ": --frames " + std::to_string(range.first) + ":" + std::to_string(range.last) +
                     " is outside the bag's " + std::to_string(n) + " associated frames");
  const CameraModel& camera = reader_.camera();
  if (options.undistort && !camera.distortion.none()) undistorter_.emplace(camera.intrinsics, camera.distortion);
  if (!options.bag.groundtruth.empty()) groundtruth_ = readTrajectory(options.bag.groundtruth);
}

std::optional<RgbdFrame> BagSource::next() {
  if (next_ > last_) return std::nullopt;
  return rgbdFrameOf(reader_.read(next_++), undistorter_ ? &*undistorter_ : nullptr);
}

cv::Mat BagSource::toRawPixels(const cv::Mat& image) const {
  return undistorter_ ? undistorter_->toRawPixels(image) : image;
}

}  // namespace ff
