// Augmenting static sequences: compositing with a depth test, exact masks, interpolated poses.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <vector>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "flowfusion/core/error.h"
#include "flowfusion/io/trajectory_io.h"
#include "flowfusion/synth/synthetic_scene.h"
#include "testing/test_util.h"

namespace fs = std::filesystem;

namespace {

// A small static sequence (the static twin of a synthetic scene) with ground truth.
std::string writeStatic(const fs::path& dir, int frames = 6) {
  ff::synth::SynthConfig c;
  c.seed = 5;
  c.width = 160;
  c.height = 120;
  c.frames = frames;
  c.objects = 0;
  c.noise = false;
  ff::synth::writeSequence(ff::synth::SyntheticScene(c), dir.string());
  fs::remove_all(dir / "masks");
  return dir.string();
}

ff::synth::AugmentConfig noiseless(int objects = 2) {
  ff::synth::AugmentConfig c;
  c.objects = objects;
  c.noise = false;
  c.seed = 3;
  return c;
}

// The truth mask an augmented sequence holds for the frame at `timestamp`.
cv::Mat maskAt(const ff::TumSequence& seq, double timestamp) {
  return cv::imread((fs::path(*seq.masksDir()) / (ff::timestampName(timestamp) + ".png")).string(), cv::IMREAD_UNCHANGED);
}

// The augmented sequence has the source's poses and timestamps; its mask marks exactly the pixels
// where the inserted depth replaced the real one (in front of it or where it had none). Returns the
// number of mask pixels.
int expectCompositedWithExactMasks(const std::string& in, const std::string& out, size_t frames) {
  const auto src = ff::TumSequence::open(in), dst = ff::TumSequence::open(out);
  EXPECT_EQ(dst.size(), frames);
  EXPECT_TRUE(dst.masksDir());
  EXPECT_TRUE(dst.groundtruth());
  if (dst.size() != frames || !dst.masksDir() || !dst.groundtruth()) return 0;
  EXPECT_TRUE(fs::exists(fs::path(out) / "scene.json"));
  EXPECT_NEAR(dst.camera().fx, src.camera().fx, 1e-9);
  int mask_total = 0;
  for (size_t i = 0; i < frames; ++i) {
    const auto a = src.load(i), b = dst.load(i);
    EXPECT_NEAR(a.timestamp, b.timestamp, 1e-9);
    ff::SE3 Ta, Tb;
    EXPECT_TRUE(ff::interpolatePose(*src.groundtruth(), a.timestamp, Ta));
    EXPECT_TRUE(ff::interpolatePose(*dst.groundtruth(), b.timestamp, Tb));
    EXPECT_LT(ff::translationNorm(Ta.inverse() * Tb), 1e-4);
    const cv::Mat mask = maskAt(dst, b.timestamp);
    EXPECT_EQ(mask.size(), a.depth.size());
    if (mask.size() != a.depth.size()) return 0;
    mask_total += cv::countNonZero(mask);
    for (int v = 0; v < mask.rows; ++v)
      for (int u = 0; u < mask.cols; ++u) {
        const float za = a.depth.at<float>(v, u), zb = b.depth.at<float>(v, u);
        if (mask.at<uint8_t>(v, u)) {
          EXPECT_TRUE(za == 0 || zb < za + 1e-4) << "an object pixel must be in front of the real surface";
          EXPECT_GT(zb, 0.0f);
        } else {
          EXPECT_EQ(za, zb) << "depth outside the mask is the real depth";
        }
      }
  }
  return mask_total;
}

}  // namespace

TEST(Augment, CompositesObjectsWithDepthTestAndExactMasks) {
  ff::testing::TempDir tmp;
  const std::string in = writeStatic(tmp.path() / "static");
  const std::string out = (tmp.path() / "aug").string();
  const auto report = ff::synth::augmentSequence(in, out, noiseless());
  EXPECT_EQ(report.frames_written, 6);
  EXPECT_TRUE(report.dropped_timestamps.empty());
  EXPECT_GT(expectCompositedWithExactMasks(in, out, 6), 500) << "objects are placed in view of the first frames";
}

TEST(Augment, PeopleWalkInViewWithExactMasks) {
  ff::testing::TempDir tmp;
  const std::string in = writeStatic(tmp.path() / "static");
  const std::string out = (tmp.path() / "aug").string();
  auto config = noiseless(0);
  config.people = 2;
  ff::synth::augmentSequence(in, out, config);
  EXPECT_GT(expectCompositedWithExactMasks(in, out, 6), 500) << "people walk in view of the first frames";
}

namespace {

// Cuts `hole` (clipped to the image) into every depth image of a static sequence and sets the 2-px
// ring around it to ring_m metres (0: the ring keeps the real depth); with `paint`, the colour
// images get that colour inside the hole.
void cutHole(const std::string& dir, const cv::Rect& hole, double ring_m, std::optional<cv::Scalar> paint = {}) {
  for (const auto& entry : fs::directory_iterator(fs::path(dir) / "depth")) {
    cv::Mat depth = cv::imread(entry.path().string(), cv::IMREAD_UNCHANGED);
    const cv::Rect image(0, 0, depth.cols, depth.rows), ring(hole.x - 2, hole.y - 2, hole.width + 4, hole.height + 4);
    if (ring_m > 0) depth(ring & image).setTo(cv::Scalar(ring_m * 5000.0));
    depth(hole & image).setTo(cv::Scalar(0));
    cv::imwrite(entry.path().string(), depth);
  }
  if (!paint) return;
  for (const auto& entry : fs::directory_iterator(fs::path(dir) / "rgb")) {
    cv::Mat color = cv::imread(entry.path().string(), cv::IMREAD_UNCHANGED);
    color(hole & cv::Rect(0, 0, color.cols, color.rows)).setTo(*paint);
    cv::imwrite(entry.path().string(), color);
  }
}

// Mask pixels of frame `index` of an augmented sequence inside `box`.
int maskPixelsIn(const std::string& dir, size_t index, const cv::Rect& box) {
  const auto seq = ff::TumSequence::open(dir);
  const cv::Mat mask = maskAt(seq, seq.load(index).timestamp);
  return cv::countNonZero(mask(box));
}

// The frame of an augmented sequence where the objects cover the most, and their centroid there.
struct MostCovered {
  size_t frame = 0;
  cv::Point centre;
  double pixels = 0;
};
MostCovered mostCovered(const std::string& dir) {
  const auto seq = ff::TumSequence::open(dir);
  MostCovered best;
  for (size_t i = 0; i < seq.size(); ++i) {
    const cv::Moments mo = cv::moments(maskAt(seq, seq.load(i).timestamp), true);
    if (mo.m00 > best.pixels)
      best = {i, cv::Point(static_cast<int>(mo.m10 / mo.m00), static_cast<int>(mo.m01 / mo.m00)), mo.m00};
  }
  return best;
}

}  // namespace

// A hole in the real depth that nearer valid depth encloses (a black screen's speckles) hides the
// objects behind that surface; a hole in a far wall shows them.
TEST(Augment, AHoleEnclosedByNearerDepthHidesTheObjectsBehindIt) {
  ff::testing::TempDir tmp;
  const std::string in = writeStatic(tmp.path() / "static");
  const std::string plain = (tmp.path() / "plain").string();
  ff::synth::augmentSequence(in, plain, noiseless());
  // The hole goes where the objects cover the most.
  const MostCovered best = mostCovered(plain);
  ASSERT_GT(best.pixels, 400) << "the objects cover a hole's worth of one frame";
  const int r = 8;
  const cv::Rect hole(best.centre.x - r, best.centre.y - r, 2 * r, 2 * r);
  ASSERT_GT(maskPixelsIn(plain, best.frame, hole), 50) << "the objects cover the hole's place";

  const std::string in_wall = writeStatic(tmp.path() / "wall"), in_screen = writeStatic(tmp.path() / "screen");
  cutHole(in_wall, hole, 0);
  cutHole(in_screen, hole, 0.3);
  const std::string out_wall = (tmp.path() / "aug_wall").string(), out_screen = (tmp.path() / "aug_screen").string();
  ff::synth::augmentSequence(in_wall, out_wall, noiseless());
  ff::synth::augmentSequence(in_screen, out_screen, noiseless());
  EXPECT_GT(maskPixelsIn(out_wall, best.frame, hole), 50) << "objects show through a hole in the wall behind them";
  EXPECT_EQ(maskPixelsIn(out_screen, best.frame, hole), 0) << "a screen 0.3 m away hides what lies behind its hole";
}

// A black surface returns no depth: a hole on black pixels that the image's edge cuts (a black
// screen at the border, too large for its own frame to enclose) continues the surface beside it and
// hides the objects behind that; the same hole on grey pixels (the room beyond the sensor's range)
// shows them (generator version 3; HoleTest::Enclosed, version 2's test, shows them in both).
TEST(Augment, AHoleOnBlackPixelsCutByTheImagesEdgeHidesTheObjectsBehindTheSurfaceBesideIt) {
  ff::testing::TempDir tmp;
  const std::string plain = (tmp.path() / "plain").string();
  ff::synth::augmentSequence(writeStatic(tmp.path() / "static"), plain, noiseless());
  const MostCovered best = mostCovered(plain);
  ASSERT_GT(best.pixels, 400) << "the objects cover a hole's worth of one frame";
  // From just left of the objects' centre to the right edge, taller than the reach (a tenth of the
  // width) that encloses a hole from above and below; judged in its middle.
  const cv::Rect hole(best.centre.x - 4, best.centre.y - 20, 10000, 40), middle(best.centre.x - 2, best.centre.y - 3, 6, 6);
  ASSERT_GT(maskPixelsIn(plain, best.frame, middle), 10) << "the objects cover the hole's middle";

  const std::string in_black = writeStatic(tmp.path() / "black"), in_grey = writeStatic(tmp.path() / "grey");
  cutHole(in_black, hole, 0.3, cv::Scalar(0, 0, 0));
  cutHole(in_grey, hole, 0.3, cv::Scalar(128, 128, 128));
  const std::string out_black = (tmp.path() / "aug_black").string(), out_grey = (tmp.path() / "aug_grey").string();
  ff::synth::augmentSequence(in_black, out_black, noiseless());
  ff::synth::augmentSequence(in_grey, out_grey, noiseless());
  EXPECT_EQ(maskPixelsIn(out_black, best.frame, middle), 0) << "a black screen 0.3 m away hides what lies behind it";
  EXPECT_GT(maskPixelsIn(out_grey, best.frame, middle), 10) << "objects show in a grey hole open to the image's edge";

  auto version2 = noiseless();
  version2.holes = ff::synth::HoleTest::Enclosed;
  const std::string out_version2 = (tmp.path() / "aug_version2").string();
  ff::synth::augmentSequence(in_black, out_version2, version2);
  EXPECT_GT(maskPixelsIn(out_version2, best.frame, middle), 10) << "version 2's test shows them through the black hole";
}

// A depth camera sees less than the colour camera: a registered depth image has no depth in a band
// at the image's edges, for the room and for what passes in front of it. BandDepth::None (the
// default, generator version 4) pastes an object there in the colour and the mask only; Drawn
// (generator version 3) gives it its depth.
TEST(Augment, AnObjectInTheSensorsBandHasNoDepthThereUnlessDrawn) {
  ff::testing::TempDir tmp;
  const std::string in = writeStatic(tmp.path() / "static");
  // A tenth of the image at each edge: 16 columns, 12 rows.
  const std::vector<cv::Rect> band{{0, 0, 16, 120}, {144, 0, 16, 120}, {0, 0, 160, 12}, {0, 108, 160, 12}};
  for (const cv::Rect& r : band) cutHole(in, r, 0);
  const std::string drawn = (tmp.path() / "drawn").string(), none = (tmp.path() / "none").string();
  auto config = noiseless(4);
  EXPECT_EQ(config.band_depth, ff::synth::BandDepth::None);
  ff::synth::augmentSequence(in, none, config);
  config.band_depth = ff::synth::BandDepth::Drawn;
  ff::synth::augmentSequence(in, drawn, config);
  const auto a = ff::TumSequence::open(drawn), b = ff::TumSequence::open(none);
  ASSERT_EQ(a.size(), b.size());
  cv::Mat edges(120, 160, CV_8U, cv::Scalar(0));
  for (const cv::Rect& r : band) edges(r).setTo(255);
  int in_band = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    const auto fa = a.load(i), fb = b.load(i);
    const cv::Mat mask = maskAt(a, fa.timestamp), pasted_in_band = (mask > 0) & edges;
    EXPECT_EQ(cv::countNonZero(mask != maskAt(b, fb.timestamp)), 0) << "the same objects in the mask";
    EXPECT_EQ(cv::norm(fa.color, fb.color, cv::NORM_INF), 0) << "and in the colour";
    EXPECT_EQ(cv::countNonZero((fa.depth > 0) & pasted_in_band), cv::countNonZero(pasted_in_band));
    EXPECT_EQ(cv::countNonZero((fb.depth > 0) & edges), 0) << "no depth in the band";
    cv::Mat same = fa.depth == fb.depth;
    EXPECT_EQ(cv::countNonZero(~same & ~edges), 0) << "the same depth elsewhere";
    in_band += cv::countNonZero(pasted_in_band);
  }
  EXPECT_GT(in_band, 50) << "the objects pass through a band";
}

TEST(Augment, DropsFramesWithoutGroundTruthPose) {
  ff::testing::TempDir tmp;
  const std::string in = writeStatic(tmp.path() / "static", 8);
  // Remove poses around frames 3..4 so that their gap (5 frames = 0.17 s) exceeds max_pose_gap.
  auto gt = ff::readTrajectory(in + "/groundtruth.txt");
  gt.erase(gt.begin() + 2, gt.begin() + 6);
  ff::writeTrajectory(in + "/groundtruth.txt", gt);
  const auto report = ff::synth::augmentSequence(in, (tmp.path() / "aug").string(), noiseless(1));
  EXPECT_EQ(report.frames_written, 4);
  EXPECT_EQ(report.dropped_timestamps.size(), 4u);
}

TEST(Augment, FrameRangeAndNoise) {
  ff::testing::TempDir tmp;
  const std::string in = writeStatic(tmp.path() / "static");
  auto c = noiseless();
  c.noise = true;
  c.first_frame = 2;
  c.last_frame = 4;
  const auto report = ff::synth::augmentSequence(in, (tmp.path() / "aug").string(), c);
  EXPECT_EQ(report.frames_written, 3);
  EXPECT_EQ(ff::TumSequence::open((tmp.path() / "aug").string()).size(), 3u);
}

TEST(Augment, BadInputsAreInputErrors) {
  ff::testing::TempDir tmp;
  EXPECT_THROW(ff::synth::augmentSequence((tmp.path() / "missing").string(), (tmp.path() / "o1").string(), noiseless()),
               ff::InputError);
  const std::string in = writeStatic(tmp.path() / "static", 3);
  auto c = noiseless();
  c.first_frame = 5;
  EXPECT_THROW(ff::synth::augmentSequence(in, (tmp.path() / "o2").string(), c), ff::InputError);
  c = noiseless();
  c.objects = 0;
  EXPECT_THROW(ff::synth::augmentSequence(in, (tmp.path() / "o3").string(), c), ff::InputError);
  const fs::path busy = tmp.path() / "busy";
  fs::create_directories(busy);
  std::ofstream(busy / "x.txt") << "x";
  EXPECT_THROW(ff::synth::augmentSequence(in, busy.string(), noiseless()), ff::InputError);
  EXPECT_NO_THROW(ff::synth::augmentSequence(in, busy.string(), noiseless(), {}, true));
  fs::remove(fs::path(in) / "groundtruth.txt");
  try {
    ff::synth::augmentSequence(in, (tmp.path() / "o4").string(), noiseless());
    FAIL() << "expected InputError";
  } catch (const ff::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("groundtruth"), std::string::npos) << e.what();
  }
}

TEST(Augment, RealFr1XyzFrames) {
  FF_REQUIRE_SHARED_DATA(dir);
  ff::testing::TempDir tmp;
  ff::synth::AugmentConfig c;
  c.last_frame = 3;
  const auto report = ff::synth::augmentSequence(dir, tmp.str(), c);
  EXPECT_EQ(report.frames_written + static_cast<int>(report.dropped_timestamps.size()), 4);
  ASSERT_GT(report.frames_written, 0);
  const auto seq = ff::TumSequence::open(tmp.str());
  EXPECT_NEAR(seq.camera().fx, 517.3, 1e-6);
  ASSERT_TRUE(seq.masksDir());
  const auto f = seq.load(0);
  const cv::Mat mask = maskAt(seq, f.timestamp);
  EXPECT_GT(cv::countNonZero(mask), 1000) << "objects at 0.7-2 m in front of the first camera";
  // The real depth keeps its own stamp (fr1/xyz: 3.6 ms or more after the colour's), which the
  // pipeline reads as the depth's time.
  const auto real = ff::TumSequence::open(dir);
  for (size_t i = 0; i < seq.size(); ++i) {
    const auto a = real.load(i), b = seq.load(i);
    ASSERT_NEAR(a.timestamp, b.timestamp, 1e-9);
    EXPECT_GT(std::abs(a.depth_timestamp - a.timestamp), 1e-3);
    EXPECT_NEAR(b.depth_timestamp, a.depth_timestamp, 1e-6) << "frame " << i;
  }
}

TEST(AugmentCli, RunsOnStaticSequence) {
  ff::testing::TempDir tmp;
  const std::string in = writeStatic(tmp.path() / "static", 4);
  const std::string out = (tmp.path() / "aug").string();
  auto r = ff::testing::runFlowfusion("augment " + in + " " + out + " --frames 1:2 --objects 1");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(ff::TumSequence::open(out).size(), 2u);
  r = ff::testing::runFlowfusion("augment " + in + " " + out + " --frames x");
  EXPECT_EQ(r.status, 2) << r.output;
  r = ff::testing::runFlowfusion("augment " + (tmp.path() / "none").string() + " " + out + "2");
  EXPECT_EQ(r.status, 2) << r.output;
}
