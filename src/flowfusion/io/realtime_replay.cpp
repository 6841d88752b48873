#include "flowfusion/io/realtime_replay.h"

#include <cmath>

#include "flowfusion/core/error.h"

namespace ff {

RealtimeReplay::RealtimeReplay(FrameSource& recording, double rate)
    : recording_(recording), rate_(rate), queue_(recording.camera(), recording.name()) {
  if (!std::isfinite(rate) || rate <= 0)
    throw InputError("the real-time rate must be a positive, finite factor of the recorded speed (got " +
                     std::to_string(rate) + ")");
}

RealtimeReplay::~RealtimeReplay() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  stop_requested_.notify_all();
  if (worker_.joinable()) worker_.join();
}

std::optional<RgbdFrame> RealtimeReplay::next() {
  if (!worker_.joinable()) worker_ = std::thread([this] { play(); });
  return queue_.next();
}

bool RealtimeReplay::stopBefore(std::chrono::steady_clock::time_point due) {
  std::unique_lock lock(mutex_);
  return stop_requested_.wait_until(lock, due, [this] { return stopping_; });
}

void RealtimeReplay::play() {
  using Clock = std::chrono::steady_clock;
  try {
    std::optional<double> first_s;  // the recording's time of its first frame
    Clock::time_point start;
    while (std::optional<RgbdFrame> frame = recording_.next()) {
      if (!first_s) {
        first_s = frame->timestamp;
        start = Clock::now();
      }
      const std::chrono::duration<double> after_start((frame->timestamp - *first_s) / rate_);
      if (stopBefore(start + std::chrono::duration_cast<Clock::duration>(after_start))) return;
      queue_.offer(std::move(*frame));
    }
    queue_.close();
  } catch (...) {
    queue_.fail(std::current_exception());
  }
}

}  // namespace ff
