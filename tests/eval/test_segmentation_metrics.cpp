#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include "flowfusion/core/error.h"
#include "flowfusion/eval/segmentation_metrics.h"
#include "testing/test_util.h"

namespace ff::eval {
namespace {

cv::Mat rectMask(int x, int y, int w, int h, cv::Size size = {40, 30}) {
  cv::Mat m(size, CV_8UC1, cv::Scalar(0));
  if (w > 0 && h > 0) m(cv::Rect(x, y, w, h)).setTo(255);
  return m;
}

TEST(CompareMasks, OverlappingRectanglesHaveKnownScores) {
  // GT: 10x10 at (0,0) = 100 px; EST: 10x10 at (5,0) = 100 px; overlap 5x10 = 50 px.
  const auto s = compareMasks(rectMask(0, 0, 10, 10), rectMask(5, 0, 10, 10));
  EXPECT_EQ(s.true_positive, 50);
  EXPECT_EQ(s.false_positive, 50);
  EXPECT_EQ(s.false_negative, 50);
  EXPECT_DOUBLE_EQ(s.iou, 50.0 / 150.0);
  EXPECT_DOUBLE_EQ(s.precision, 0.5);
  EXPECT_DOUBLE_EQ(s.recall, 0.5);
}

TEST(CompareMasks, ThresholdIsAbove127) {
  cv::Mat gt(4, 4, CV_8UC1, cv::Scalar(128));
  cv::Mat est(4, 4, CV_8UC1, cv::Scalar(127));
  const auto s = compareMasks(gt, est);
  EXPECT_EQ(s.false_negative, 16);
  EXPECT_EQ(s.true_positive, 0);
}

TEST(CompareMasks, EmptyClassConventions) {
  const auto both_empty = compareMasks(rectMask(0, 0, 0, 0), rectMask(0, 0, 0, 0));
  EXPECT_EQ(both_empty.iou, 1);
  EXPECT_EQ(both_empty.precision, 1);
  EXPECT_EQ(both_empty.recall, 1);
  const auto missed = compareMasks(rectMask(0, 0, 5, 5), rectMask(0, 0, 0, 0));
  EXPECT_EQ(missed.iou, 0);
  EXPECT_EQ(missed.precision, 1);  // nothing predicted: no false positive
  EXPECT_EQ(missed.recall, 0);
  const auto spurious = compareMasks(rectMask(0, 0, 0, 0), rectMask(0, 0, 5, 5));
  EXPECT_EQ(spurious.iou, 0);
  EXPECT_EQ(spurious.precision, 0);
  EXPECT_EQ(spurious.recall, 1);
}

TEST(CompareMasks, SizeMismatchIsInputErrorNamingBoth) {
  try {
    compareMasks(rectMask(0, 0, 5, 5), rectMask(0, 0, 5, 5, {20, 30}), "gt/1.png", "est/1.png");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("gt/1.png"), std::string::npos) << msg;
    EXPECT_NE(msg.find("est/1.png"), std::string::npos) << msg;
  }
}

TEST(EvaluateSegmentation, FoldersMatchedByTimestampWithMeanAndPooledScores) {
  ff::testing::TempDir dir;
  const auto gt_dir = dir.path() / "gt", est_dir = dir.path() / "est";
  std::filesystem::create_directories(gt_dir);
  std::filesystem::create_directories(est_dir);
  // Frame 1: IoU 1/3 (as above). Frame 2: perfect 20 px. Frame 3: both empty (IoU 1).
  // Estimated stamps are 5 ms off; a 4th estimated mask has no ground truth.
  cv::imwrite((gt_dir / "100.000000.png").string(), rectMask(0, 0, 10, 10));
  cv::imwrite((est_dir / "100.005000.png").string(), rectMask(5, 0, 10, 10));
  cv::imwrite((gt_dir / "100.100000.png").string(), rectMask(20, 20, 4, 5));
  cv::imwrite((est_dir / "100.105000.png").string(), rectMask(20, 20, 4, 5));
  cv::imwrite((gt_dir / "100.200000.png").string(), rectMask(0, 0, 0, 0));
  cv::imwrite((est_dir / "100.195000.png").string(), rectMask(0, 0, 0, 0));
  cv::imwrite((est_dir / "105.000000.png").string(), rectMask(0, 0, 3, 3));
  const auto r = evaluateSegmentation(gt_dir.string(), est_dir.string());
  EXPECT_EQ(r.frames, 3u);
  EXPECT_EQ(r.gt_unmatched, 0u);
  EXPECT_EQ(r.est_unmatched, 1u);
  EXPECT_NEAR(r.mean_iou, (1.0 / 3 + 1 + 1) / 3, 1e-12);
  EXPECT_NEAR(r.mean_precision, (0.5 + 1 + 1) / 3, 1e-12);
  EXPECT_NEAR(r.mean_recall, (0.5 + 1 + 1) / 3, 1e-12);
  // Pooled: TP 50+20, FP 50, FN 50.
  EXPECT_EQ(r.pooled.true_positive, 70);
  EXPECT_NEAR(r.pooled.iou, 70.0 / 170.0, 1e-12);
  EXPECT_NEAR(r.pooled.precision, 70.0 / 120.0, 1e-12);
  // Each pair with its scores, in time order.
  ASSERT_EQ(r.per_frame.size(), 3u);
  const double stamps[] = {100.0, 100.1, 100.2}, ious[] = {1.0 / 3, 1, 1};
  for (int k = 0; k < 3; ++k) {
    EXPECT_DOUBLE_EQ(r.per_frame[k].timestamp, stamps[k]);
    EXPECT_NEAR(r.per_frame[k].scores.iou, ious[k], 1e-12);
  }
  EXPECT_EQ(r.per_frame[0].pixels, 40 * 30);
  // Frame 1 found its mover in part with as many missed as false pixels; nothing else lost.
  EXPECT_NEAR(r.iou_loss.mover_partly_found, (1 - 1.0 / 3) / 3, 1e-12);
  EXPECT_NEAR(r.iou_loss.false_marks_without_mover + r.iou_loss.small_mover_missed + r.iou_loss.mover_missed +
                  r.iou_loss.false_marks_over_misses,
              0.0, 1e-12);
  EXPECT_EQ(std::filesystem::path(r.per_frame[0].gt_path).filename(), "100.000000.png");
  EXPECT_EQ(std::filesystem::path(r.per_frame[0].est_path).filename(), "100.005000.png");
}

// Frames of a 100 x 100 image, one of each kind, with known losses that add up to 1 - mean IoU.
TEST(IouLoss, EachFrameLossGoesToWhatTheFrameShows) {
  const auto frame = [](int64_t tp, int64_t fp, int64_t fn) {
    FrameMaskScores f;
    f.scores = scoresFromCounts(tp, fp, fn);
    f.pixels = 100 * 100;
    return f;
  };
  const std::vector<FrameMaskScores> frames = {
      frame(0, 30, 0),     // no mover, 30 pixels marked: IoU 0
      frame(0, 0, 50),     // a mover of 50 pixels (under 0.65 % of 10,000), missed: IoU 0
      frame(10, 0, 990),   // a mover of 1,000 pixels, a hundredth found: IoU 0.01
      frame(600, 300, 100),  // found, more false than missed pixels: IoU 0.6
      frame(600, 100, 300),  // found, more missed than false pixels: IoU 0.6
      frame(400, 0, 0),    // found exactly: IoU 1, nothing lost
  };
  const IouLoss loss = iouLoss(frames);
  const double n = 6;
  EXPECT_NEAR(loss.false_marks_without_mover, 1 / n, 1e-12);
  EXPECT_NEAR(loss.small_mover_missed, 1 / n, 1e-12);
  EXPECT_NEAR(loss.mover_missed, 0.99 / n, 1e-12);
  EXPECT_NEAR(loss.false_marks_over_misses, 0.4 / n, 1e-12);
  EXPECT_NEAR(loss.mover_partly_found, 0.4 / n, 1e-12);
  double mean_iou = 0;
  for (const FrameMaskScores& f : frames) mean_iou += f.scores.iou / n;
  EXPECT_NEAR(loss.false_marks_without_mover + loss.small_mover_missed + loss.mover_missed +
                  loss.false_marks_over_misses + loss.mover_partly_found,
              1 - mean_iou, 1e-12);
  // The same 50-pixel mover in a 40 x 30 image is 4 % of it: not small.
  std::vector<FrameMaskScores> small_image = {frame(0, 0, 50)};
  small_image[0].pixels = 40 * 30;
  EXPECT_NEAR(iouLoss(small_image).mover_missed, 1.0, 1e-12);
  // A mover a third found is not missed, though the frame's IoU is under 0.2 (false marks beside it).
  EXPECT_NEAR(iouLoss({frame(300, 1200, 600)}).false_marks_over_misses, 1 - 300.0 / 2100, 1e-12);
}

TEST(EvaluateSegmentation, BadFoldersAreInputErrors) {
  ff::testing::TempDir dir;
  const auto gt_dir = dir.path() / "gt", est_dir = dir.path() / "est";
  EXPECT_THROW(evaluateSegmentation(gt_dir.string(), est_dir.string()), InputError);  // missing
  std::filesystem::create_directories(gt_dir);
  std::filesystem::create_directories(est_dir);
  EXPECT_THROW(evaluateSegmentation(gt_dir.string(), est_dir.string()), InputError);  // empty
  cv::imwrite((gt_dir / "1.000000.png").string(), rectMask(0, 0, 5, 5));
  cv::imwrite((est_dir / "2.000000.png").string(), rectMask(0, 0, 5, 5));
  EXPECT_THROW(evaluateSegmentation(gt_dir.string(), est_dir.string()), InputError);  // no match in time
  cv::imwrite((est_dir / "1.000000.png").string(), rectMask(0, 0, 5, 5, {20, 20}));
  try {
    evaluateSegmentation(gt_dir.string(), est_dir.string());
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("1.000000.png"), std::string::npos) << e.what();
  }
}

TEST(EvaluateStaticMasks, SharesOfEachFrameMeanAndFramesAbove) {
  ff::testing::TempDir dir;
  // 40x30 = 1200 px: nothing, 60 px (5 %, not above), 120 px (10 %).
  cv::imwrite((dir.path() / "1.000000.png").string(), rectMask(0, 0, 0, 0));
  cv::imwrite((dir.path() / "1.033000.png").string(), rectMask(0, 0, 10, 6));
  cv::imwrite((dir.path() / "1.066000.png").string(), rectMask(0, 0, 10, 12));
  const StaticMaskResult r = evaluateStaticMasks(dir.path().string(), 0.05);
  ASSERT_EQ(r.frames, 3u);
  EXPECT_DOUBLE_EQ(r.per_frame[1].marked, 0.05);
  EXPECT_DOUBLE_EQ(r.mean_marked, 0.05);
  EXPECT_DOUBLE_EQ(r.max_marked, 0.1);
  EXPECT_EQ(r.frames_above, 1u);
  EXPECT_DOUBLE_EQ(r.fraction_above, 1.0 / 3);
  EXPECT_THROW(evaluateStaticMasks((dir.path() / "none").string()), InputError);
  EXPECT_THROW(evaluateStaticMasks(dir.path().string(), 1.5), InputError);
}

}  // namespace
}  // namespace ff::eval
