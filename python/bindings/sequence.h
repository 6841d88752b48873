#pragma once
// ff.TumSequence: a TUM-layout folder over a range of its frames, indexable and iterable in Python,
// and ff.Frame, one of its frames with what takes a result back to the raw image's pixels.
#include <memory>

#include "flowfusion/io/tum_folder_source.h"

namespace ff::py_bind {

// A frame as the sequence loaded it (undistorted when its camera has distortion), the mapping of
// its pixels back to the raw image file's (null when they are the same) and the folder it came from.
struct PyFrame {
  RgbdFrame frame;
  std::shared_ptr<const Undistorter> raw;
  std::string sequence_dir;
};

class PySequence {
 public:
  PySequence(const std::string& path, const SequenceOptions& options, FrameRange range);

  size_t size() const { return count_; }
  PyFrame load(size_t i) const {
    return {source_->sequence().load(first_ + i), source_->sequence().sharedUndistorter(), source_->sequence().dir()};
  }
  double timestamp(size_t i) const { return source_->sequence().entry(first_ + i).rgb_timestamp; }
  // The frame source (raw pixels, ground truth) for the files sink.
  const FrameSource& source() const { return *source_; }
  const TumSequence& sequence() const { return source_->sequence(); }

 private:
  std::unique_ptr<TumFolderSource> source_;
  size_t first_ = 0, count_ = 0;
};

}  // namespace ff::py_bind
