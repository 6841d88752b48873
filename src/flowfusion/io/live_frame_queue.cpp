#include "flowfusion/io/live_frame_queue.h"

namespace ff {

LiveFrameQueue::LiveFrameQueue(CameraIntrinsics camera, std::string name)
    : camera_(std::move(camera)), name_(std::move(name)) {}

void LiveFrameQueue::offer(RgbdFrame frame) {
  {
    std::lock_guard lock(mutex_);
    if (closed_) return;
    ++arrivals_.offered;
    if (waiting_) ++arrivals_.dropped;
    waiting_ = std::move(frame);
    waiting_offered_at_ = std::chrono::steady_clock::now();
  }
  offered_.notify_all();
}

void LiveFrameQueue::close() {
  {
    std::lock_guard lock(mutex_);
    closed_ = true;
  }
  offered_.notify_all();
}

void LiveFrameQueue::fail(std::exception_ptr error) {
  {
    std::lock_guard lock(mutex_);
    if (!error_) error_ = std::move(error);
    closed_ = true;
  }
  offered_.notify_all();
}

std::optional<RgbdFrame> LiveFrameQueue::next() {
  std::unique_lock lock(mutex_);
  offered_.wait(lock, [this] { return waiting_ || closed_; });
  if (!waiting_) {
    if (error_) std::rethrow_exception(error_);
    return std::nullopt;
  }
  std::optional<RgbdFrame> frame = std::move(waiting_);
  waiting_.reset();
  arrivals_.last_offered_at = waiting_offered_at_;
  return frame;
}

std::optional<Arrivals> LiveFrameQueue::arrivals() const {
  std::lock_guard lock(mutex_);
  return arrivals_;
}

}  // namespace ff
