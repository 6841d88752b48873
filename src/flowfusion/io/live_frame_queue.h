#pragma once
// A live frame source: frames arrive on their own clock (a camera driver's callback, a ROS
// subscriber, a recording replayed at its recorded times, io/realtime_replay.h) and the system
// takes the newest one whenever it is ready for the next. It is a queue of one: a frame offered
// while another is still waiting replaces it, and the replaced frame counts as dropped, so a
// system slower than the sensor skips frames and stays live instead of working through a backlog
// that grows without bound.
#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <optional>
#include <string>

#include "flowfusion/io/frame_source.h"

namespace ff {

class LiveFrameQueue : public FrameSource {
 public:
  LiveFrameQueue(CameraIntrinsics camera, std::string name);

  // From any thread: the frame waits for next(), replacing (dropping) the one waiting, if any.
  // Ignored after close().
  void offer(RgbdFrame frame);
  // No more frames: next() returns the one still waiting, then nullopt.
  void close();
  // The producer failed: next() returns the frame still waiting, then rethrows `error`.
  void fail(std::exception_ptr error);

  const CameraIntrinsics& camera() const override { return camera_; }
  // Waits for a frame to be offered (or for close()); the consumer's thread only.
  std::optional<RgbdFrame> next() override;
  std::optional<size_t> remaining() const override { return std::nullopt; }
  std::string name() const override { return name_; }
  std::optional<Arrivals> arrivals() const override;

 private:
  const CameraIntrinsics camera_;
  const std::string name_;
  mutable std::mutex mutex_;
  std::condition_variable offered_;
  std::optional<RgbdFrame> waiting_;
  std::chrono::steady_clock::time_point waiting_offered_at_;
  Arrivals arrivals_;
  std::exception_ptr error_;
  bool closed_ = false;
};

}  // namespace ff
