#pragma once
// A recording replayed as a live camera (`flowfusion run --realtime`): each frame is offered at
// its recorded time after the first, divided by `rate`, into a queue of one (io/live_frame_queue.h),
// so the system sees what it would see next to the sensor: the frames it is too slow for are
// dropped, never queued. This is how a user learns whether a machine keeps up before mounting it
// on a robot. The recording is read on a worker thread, the next frame decoded while the replay
// waits for its time; the replay's clock starts at the first next().
#include <condition_variable>
#include <mutex>
#include <thread>

#include "flowfusion/io/live_frame_queue.h"

namespace ff {

class RealtimeReplay : public FrameSource {
 public:
  // `recording` must outlive this object; its next() is then called on the worker thread only
  // (const members from any thread, as every source in io/ allows). `rate` > 0 and finite: 2 plays
  // twice as fast as recorded, 0.5 half as fast. Throws InputError otherwise.
  RealtimeReplay(FrameSource& recording, double rate);
  // Stops the replay after the frame it is reading, if any.
  ~RealtimeReplay() override;
  RealtimeReplay(const RealtimeReplay&) = delete;
  RealtimeReplay& operator=(const RealtimeReplay&) = delete;

  const CameraIntrinsics& camera() const override { return recording_.camera(); }
  // The newest frame offered and not yet taken; waits for one. Rethrows an error reading the
  // recording after the frames before it.
  std::optional<RgbdFrame> next() override;
  std::optional<size_t> remaining() const override { return std::nullopt; }
  std::string name() const override { return recording_.name(); }
  cv::Mat toRawPixels(const cv::Mat& image) const override { return recording_.toRawPixels(image); }
  const Trajectory* groundtruth() const override { return recording_.groundtruth(); }
  std::optional<std::string> masksDir() const override { return recording_.masksDir(); }
  std::optional<Arrivals> arrivals() const override { return queue_.arrivals(); }

  double rate() const { return rate_; }

 private:
  void play();
  // Waits until `due` or until the destructor asks to stop; true when it did.
  bool stopBefore(std::chrono::steady_clock::time_point due);

  FrameSource& recording_;
  const double rate_;
  LiveFrameQueue queue_;
  std::mutex mutex_;
  std::condition_variable stop_requested_;
  bool stopping_ = false;
  std::thread worker_;  // last; started by the first next()
};

}  // namespace ff
