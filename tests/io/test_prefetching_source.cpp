// The read-ahead source: the same frames in the same order as the source it wraps, a frame that
// cannot be read fails where the plain source fails (naming the file), and it can be dropped at
// any time without waiting for the rest of the sequence.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <thread>

#include "flowfusion/core/error.h"
#include "flowfusion/io/prefetching_source.h"
#include "flowfusion/io/tum_folder_source.h"
#include "testing/test_util.h"

namespace fs = std::filesystem;

namespace ff {
namespace {

constexpr int kFrames = 6;

// A 64x48 TUM-layout folder whose frame i has colour (i, 2i, 3i) + x and depth 1 m + i mm + y.
fs::path makeSequence(const fs::path& root) {
  fs::create_directories(root / "rgb");
  fs::create_directories(root / "depth");
  std::ofstream rgb(root / "rgb.txt"), depth(root / "depth.txt");
  for (int i = 0; i < kFrames; ++i) {
    const std::string t = std::to_string(1.0 + i / 30.0);
    cv::Mat c(48, 64, CV_8UC3), d(48, 64, CV_16U);
    for (int y = 0; y < 48; ++y)
      for (int x = 0; x < 64; ++x) {
        c.at<cv::Vec3b>(y, x) = cv::Vec3b(i + x, 2 * i + x, 3 * i + x);
        d.at<uint16_t>(y, x) = static_cast<uint16_t>(5000 + 5 * i + y);
      }
    cv::imwrite((root / "rgb" / (t + ".png")).string(), c);
    cv::imwrite((root / "depth" / (t + ".png")).string(), d);
    rgb << t << " rgb/" << t << ".png\n";
    depth << t << " depth/" << t << ".png\n";
  }
  std::ofstream(root / "camera.txt") << "50 50 31.5 23.5 64 48\n";
  return root;
}

bool same(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
}

TEST(PrefetchingSource, GivesThePlainSourcesFramesInOrder) {
  testing::TempDir tmp;
  const fs::path seq = makeSequence(tmp.path() / "seq");
  for (size_t depth : {1u, 2u, 8u}) {
    SCOPED_TRACE("depth " + std::to_string(depth));
    TumFolderSource plain(TumSequence::open(seq.string()));
    TumFolderSource inner(TumSequence::open(seq.string()));
    PrefetchingSource ahead(inner, depth);
    EXPECT_EQ(ahead.name(), plain.name());
    EXPECT_EQ(ahead.camera().fx, plain.camera().fx);
    for (int i = 0; i < kFrames; ++i) {
      ASSERT_EQ(ahead.remaining(), plain.remaining());
      const std::optional<RgbdFrame> a = ahead.next(), b = plain.next();
      ASSERT_TRUE(a && b) << "frame " << i;
      EXPECT_EQ(a->timestamp, b->timestamp);
      EXPECT_EQ(a->name, b->name);
      EXPECT_TRUE(same(a->color, b->color)) << "frame " << i;
      EXPECT_TRUE(same(a->intensity, b->intensity)) << "frame " << i;
      EXPECT_TRUE(same(a->depth, b->depth)) << "frame " << i;
    }
    EXPECT_FALSE(ahead.next());
    EXPECT_FALSE(plain.next());
    EXPECT_EQ(ahead.remaining(), std::optional<size_t>(0));
  }
}

TEST(PrefetchingSource, AnUnreadableFrameFailsInItsTurnNamingTheFile) {
  testing::TempDir tmp;
  const fs::path seq = makeSequence(tmp.path() / "seq");
  const std::string bad = std::to_string(1.0 + 3 / 30.0) + ".png";
  std::ofstream(seq / "rgb" / bad) << "this is not a PNG";
  TumFolderSource inner(TumSequence::open(seq.string()));
  PrefetchingSource ahead(inner, 4);
  // Let the worker reach the bad frame first: the frames before it still come out.
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(ahead.next()) << "frame " << i;
  const std::string message = testing::inputErrorOf([&] { ahead.next(); });
  EXPECT_NE(message.find(bad), std::string::npos) << message;
  EXPECT_NE(testing::inputErrorOf([&] { ahead.next(); }), "no InputError");
}

// A live source (no known length) that never ends and counts its reads.
class EndlessSource : public FrameSource {
 public:
  explicit EndlessSource(std::atomic<int>& reads) : reads_(reads) {}
  const CameraIntrinsics& camera() const override { return camera_; }
  std::optional<RgbdFrame> next() override {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    RgbdFrame f;
    f.timestamp = reads_++;
    f.depth = cv::Mat(4, 4, CV_32F, cv::Scalar(1.0f));
    return f;
  }
  std::optional<size_t> remaining() const override { return std::nullopt; }
  std::string name() const override { return "endless"; }

 private:
  CameraIntrinsics camera_;
  std::atomic<int>& reads_;
};

TEST(PrefetchingSource, DroppedEarlyStopsReading) {
  std::atomic<int> reads{0};
  EndlessSource endless(reads);
  {
    PrefetchingSource ahead(endless, 3);
    EXPECT_EQ(ahead.remaining(), std::nullopt);
    for (int i = 0; i < 2; ++i) EXPECT_EQ(ahead.next()->timestamp, i);
    EXPECT_EQ(ahead.remaining(), std::nullopt);
  }  // the destructor returns: the worker finished its read and stopped
  const int at_drop = reads.load();
  EXPECT_LE(at_drop, 2 + 3 + 1);  // taken, read ahead, the one in progress
  std::this_thread::sleep_for(std::chrono::milliseconds(30));
  EXPECT_EQ(reads.load(), at_drop);
}

}  // namespace
}  // namespace ff
