#include "flowfusion/io/prefetching_source.h"

#include <stdexcept>

namespace ff {

PrefetchingSource::PrefetchingSource(FrameSource& source, size_t depth)
    : source_(source), depth_(depth), remaining_(source.remaining()) {
  if (depth_ == 0) throw std::invalid_argument("PrefetchingSource: depth must be at least 1");
  worker_ = std::thread([this] { work(); });
}

PrefetchingSource::~PrefetchingSource() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
  worker_.join();
}

void PrefetchingSource::work() {
  for (;;) {
    {
      std::unique_lock lock(mutex_);
      changed_.wait(lock, [this] { return stopping_ || ready_.size() < depth_; });
      if (stopping_) return;
    }
    std::optional<RgbdFrame> frame;
    std::exception_ptr error;
    try {
      frame = source_.next();
    } catch (...) {
      error = std::current_exception();
    }
    {
      std::lock_guard lock(mutex_);
      if (frame) ready_.push_back(std::move(*frame));
      error_ = error;
      finished_ = !frame;
    }
    changed_.notify_all();
    if (!frame) return;
  }
}

std::optional<RgbdFrame> PrefetchingSource::next() {
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [this] { return !ready_.empty() || finished_; });
  if (ready_.empty()) {
    if (error_) std::rethrow_exception(error_);
    if (remaining_) remaining_ = 0;
    return std::nullopt;
  }
  RgbdFrame frame = std::move(ready_.front());
  ready_.pop_front();
  if (remaining_ && *remaining_ > 0) --*remaining_;
  lock.unlock();
  changed_.notify_all();
  return frame;
}

std::optional<size_t> PrefetchingSource::remaining() const {
  std::lock_guard lock(mutex_);
  return remaining_;
}

}  // namespace ff
