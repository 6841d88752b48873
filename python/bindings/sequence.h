#pragma once
// ff.TumSequence: a TUM-layout folder over a range of its frames, indexable and iterable in Python.
#include <memory>

#include "flowfusion/io/tum_folder_source.h"

namespace ff::py_bind {

class PySequence {
 public:
  PySequence(const std::string& path, const SequenceOptions& options, FrameRange range);

  size_t size() const { return count_; }
  RgbdFrame load(size_t i) const { return source_->sequence().load(first_ + i); }
  double timestamp(size_t i) const { return source_->sequence().entry(first_ + i).rgb_timestamp; }
  // The frame source (raw pixels, ground truth) for the files sink.
  const FrameSource& source() const { return *source_; }
  const TumSequence& sequence() const { return source_->sequence(); }

 private:
  std::unique_ptr<TumFolderSource> source_;
  size_t first_ = 0, count_ = 0;
};

}  // namespace ff::py_bind
