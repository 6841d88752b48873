#include "flowfusion/io/tum_folder_source.h"

#include "flowfusion/core/error.h"

namespace ff {

TumFolderSource::TumFolderSource(TumSequence sequence, FrameRange range) : sequence_(std::move(sequence)) {
  const size_t n = sequence_.size();
  next_ = static_cast<size_t>(range.first);
  last_ = range.last < 0 ? n - 1 : static_cast<size_t>(range.last);
  if (next_ >= n || last_ >= n)
    throw InputError(sequence_.dir() + ": --frames " + std::to_string(range.first) + ":" +
                     std::to_string(range.last) + " is outside the sequence's " + std::to_string(n) +
                     " associated frames");
}

std::optional<RgbdFrame> TumFolderSource::next() {
  if (next_ > last_) return std::nullopt;
  return sequence_.load(next_++);
}

cv::Mat TumFolderSource::toRawPixels(const cv::Mat& image) const {
  return sequence_.undistorter() ? sequence_.undistorter()->toRawPixels(image) : image;
}

const Trajectory* TumFolderSource::groundtruth() const {
  return sequence_.groundtruth() ? &*sequence_.groundtruth() : nullptr;
}

}  // namespace ff
