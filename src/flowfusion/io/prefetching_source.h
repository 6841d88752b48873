#pragma once
// A frame source read ahead on a worker thread: while the caller processes one frame, the next
// ones are decoded (PNG, undistortion), so loading overlaps the pipeline (runSequence uses it).
// The frames are the wrapped source's, identical and in the same order; an error reading a frame
// is rethrown by the next() that would have returned that frame, after the frames before it.
#include <condition_variable>
#include <deque>
#include <exception>
#include <mutex>
#include <thread>

#include "flowfusion/io/frame_source.h"

namespace ff {

class PrefetchingSource : public FrameSource {
 public:
  // Reads up to `depth` (>= 1) frames of `source` ahead. `source` must outlive this object; its
  // next() is then called on the worker thread only, while its const members may be called from
  // other threads (every source in io/ allows that: they do not change with next()).
  PrefetchingSource(FrameSource& source, size_t depth);
  // Stops the worker: it finishes the frame it is reading, if any, and reads no more.
  ~PrefetchingSource() override;
  PrefetchingSource(const PrefetchingSource&) = delete;
  PrefetchingSource& operator=(const PrefetchingSource&) = delete;

  const CameraIntrinsics& camera() const override { return source_.camera(); }
  // Waits for the worker when the next frame is not read yet.
  std::optional<RgbdFrame> next() override;
  std::optional<size_t> remaining() const override;
  std::string name() const override { return source_.name(); }
  cv::Mat toRawPixels(const cv::Mat& image) const override { return source_.toRawPixels(image); }
  const Trajectory* groundtruth() const override { return source_.groundtruth(); }
  std::optional<std::string> masksDir() const override { return source_.masksDir(); }

 private:
  void work();

  FrameSource& source_;
  const size_t depth_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<RgbdFrame> ready_;
  std::optional<size_t> remaining_;  // frames next() will still return, when the source knew
  std::exception_ptr error_;         // the worker's error, after the frames in ready_
  bool finished_ = false;            // the worker met the end or an error
  bool stopping_ = false;            // the destructor asks the worker to stop
  std::thread worker_;               // last: starts once the members above exist
};

}  // namespace ff
