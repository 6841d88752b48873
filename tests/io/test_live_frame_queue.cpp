// Live sources: the queue of one keeps only the newest frame and counts what it replaced, and a
// recording replayed in real time offers its frames in order, never before their recorded time,
// and passes a reading error on after the frames before it.
#include <gtest/gtest.h>

#include <chrono>
#include <limits>
#include <thread>
#include <vector>

#include "flowfusion/core/error.h"
#include "flowfusion/io/live_frame_queue.h"
#include "flowfusion/io/realtime_replay.h"
#include "testing/test_util.h"

namespace ff {
namespace {

using Clock = std::chrono::steady_clock;

RgbdFrame tinyFrame(double timestamp_s) {
  RgbdFrame f;
  f.timestamp = timestamp_s;
  f.color = cv::Mat(4, 4, CV_8UC3, cv::Scalar::all(0));
  f.intensity = cv::Mat(4, 4, CV_32F, cv::Scalar(0));
  f.depth = cv::Mat(4, 4, CV_32F, cv::Scalar(1));
  return f;
}

CameraIntrinsics tinyCamera() { return CameraIntrinsics{4, 4, 1.5, 1.5, 4, 4}; }

// `frames` frames `interval_s` apart from t = 10 s, in memory; frame `fail_at` throws InputError.
class TimedSource : public FrameSource {
 public:
  TimedSource(int frames, double interval_s, int fail_at = -1)
      : frames_(frames), interval_s_(interval_s), fail_at_(fail_at), camera_(tinyCamera()) {}
  const CameraIntrinsics& camera() const override { return camera_; }
  std::optional<RgbdFrame> next() override {
    if (next_ == frames_) return std::nullopt;
    if (next_ == fail_at_) throw InputError("frame " + std::to_string(next_) + " unreadable");
    return tinyFrame(stamp(next_++));
  }
  std::optional<size_t> remaining() const override { return frames_ - next_; }
  std::string name() const override { return "timed"; }
  double stamp(int i) const { return 10.0 + i * interval_s_; }

 private:
  int frames_;
  double interval_s_;
  int fail_at_;
  CameraIntrinsics camera_;
  int next_ = 0;
};

TEST(LiveFrameQueue, AFrameOfferedWhileOneWaitsReplacesItAndCountsAsDropped) {
  LiveFrameQueue queue(tinyCamera(), "live");
  EXPECT_FALSE(queue.remaining()) << "a live source does not know how many frames will come";
  for (double t : {1.0, 2.0, 3.0}) queue.offer(tinyFrame(t));
  const std::optional<RgbdFrame> newest = queue.next();
  ASSERT_TRUE(newest);
  EXPECT_EQ(newest->timestamp, 3.0);
  Arrivals a = *queue.arrivals();
  EXPECT_EQ(a.offered, 3u);
  EXPECT_EQ(a.dropped, 2u);
  queue.offer(tinyFrame(4.0));
  EXPECT_EQ(queue.next()->timestamp, 4.0);
  a = *queue.arrivals();
  EXPECT_EQ(a.offered, 4u);
  EXPECT_EQ(a.dropped, 2u) << "a frame taken in time is not dropped";
}

TEST(LiveFrameQueue, CloseGivesTheWaitingFrameThenTheEnd) {
  LiveFrameQueue queue(tinyCamera(), "live");
  queue.offer(tinyFrame(1.0));
  queue.close();
  queue.offer(tinyFrame(2.0));
  EXPECT_EQ(queue.next()->timestamp, 1.0);
  EXPECT_FALSE(queue.next());
  EXPECT_EQ(queue.arrivals()->offered, 1u) << "frames after close() are not offered";
}

TEST(LiveFrameQueue, AProducersErrorComesAfterTheWaitingFrame) {
  LiveFrameQueue queue(tinyCamera(), "live");
  queue.offer(tinyFrame(1.0));
  queue.fail(std::make_exception_ptr(InputError("camera unplugged")));
  EXPECT_EQ(queue.next()->timestamp, 1.0);
  EXPECT_EQ(testing::inputErrorOf([&] { queue.next(); }), "camera unplugged");
}

TEST(LiveFrameQueue, NextWaitsForAFrameFromAnotherThread) {
  LiveFrameQueue queue(tinyCamera(), "live");
  std::thread producer([&] {
    queue.offer(tinyFrame(5.0));
    queue.close();
  });
  const std::optional<RgbdFrame> f = queue.next();
  producer.join();
  ASSERT_TRUE(f);
  EXPECT_EQ(f->timestamp, 5.0);
  EXPECT_LE(queue.arrivals()->last_offered_at, Clock::now());
}

TEST(RealtimeReplay, OffersTheRecordingsFramesInOrderNeverBeforeTheirTime) {
  constexpr double kIntervalS = 0.02;
  constexpr double kRate = 2.0;
  TimedSource recording(8, kIntervalS);
  RealtimeReplay replay(recording, kRate);
  EXPECT_EQ(replay.name(), "timed");
  EXPECT_FALSE(replay.remaining());
  std::vector<double> stamps;
  const Clock::time_point before_start = Clock::now();  // the replay's clock starts at the first next()
  while (std::optional<RgbdFrame> f = replay.next()) {
    const std::chrono::duration<double> since_start = Clock::now() - before_start;
    const double recorded_after_first_s = f->timestamp - recording.stamp(0);
    EXPECT_GE(since_start.count(), recorded_after_first_s / kRate - 1e-6) << "frame at " << f->timestamp;
    if (!stamps.empty()) EXPECT_GT(f->timestamp, stamps.back());
    stamps.push_back(f->timestamp);
  }
  const Arrivals a = *replay.arrivals();
  EXPECT_EQ(a.offered, 8u);
  EXPECT_EQ(stamps.size() + a.dropped, a.offered);
  EXPECT_EQ(stamps.front(), recording.stamp(0));
  EXPECT_EQ(stamps.back(), recording.stamp(7)) << "the last frame is never replaced";
}

TEST(RealtimeReplay, AnUnreadableFrameFailsAfterTheFramesBeforeIt) {
  TimedSource recording(5, 0.001, /*fail_at=*/3);
  RealtimeReplay replay(recording, 1.0);
  std::vector<double> stamps;
  const std::string error = testing::inputErrorOf([&] {
    while (std::optional<RgbdFrame> f = replay.next()) stamps.push_back(f->timestamp);
  });
  EXPECT_EQ(error, "frame 3 unreadable");
  ASSERT_FALSE(stamps.empty());
  EXPECT_EQ(stamps.back(), recording.stamp(2));
}

TEST(RealtimeReplay, CanBeDroppedWhileWaitingForAFarFrame) {
  TimedSource recording(3, 3600.0);  // an hour apart: the destructor must not wait for them
  {
    RealtimeReplay replay(recording, 1.0);
    EXPECT_EQ(replay.next()->timestamp, recording.stamp(0));
  }
  SUCCEED();
}

TEST(RealtimeReplay, RefusesARateThatIsNotAPositiveFiniteFactor) {
  TimedSource recording(2, 0.03);
  for (double rate : {0.0, -1.0, std::numeric_limits<double>::infinity(), std::numeric_limits<double>::quiet_NaN()}) {
    const std::string error = testing::inputErrorOf([&] { RealtimeReplay replay(recording, rate); });
    EXPECT_NE(error.find("rate"), std::string::npos) << rate << ": " << error;
  }
}

}  // namespace
}  // namespace ff
