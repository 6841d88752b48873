#include <gtest/gtest.h>

#include <limits>

#include "flowfusion/core/error.h"
#include "flowfusion/segmentation/small_regions.h"

namespace ff {
namespace {

// A 100 x 50 image (5000 pixels): at a share of 0.02, regions of fewer than 100 pixels are small.
cv::Mat emptyMask() { return cv::Mat(50, 100, CV_8U, cv::Scalar(0)); }

int marked(const cv::Mat& mask, const cv::Rect& r) { return cv::countNonZero(mask(r)); }

TEST(SmallRegions, ASmallRegionInsideTheViewIsDroppedALargeOneKept) {
  cv::Mat mask = emptyMask();
  mask(cv::Rect(10, 10, 9, 11)).setTo(255);  // 99 pixels
  mask(cv::Rect(40, 10, 10, 10)).setTo(255);  // 100 pixels
  mask(cv::Rect(70, 10, 5, 5)).setTo(255);   // 25 pixels, and 75 touching its corner
  mask(cv::Rect(75, 15, 15, 5)).setTo(128);  // diagonally: one 8-connected region of 100
  dropSmallInteriorRegions(mask, 0.02);
  EXPECT_EQ(marked(mask, cv::Rect(10, 10, 9, 11)), 0);
  EXPECT_EQ(marked(mask, cv::Rect(40, 10, 10, 10)), 100);
  EXPECT_EQ(cv::countNonZero(mask), 200);
}

TEST(SmallRegions, ASliceAtAnyBorderOfTheImageIsKept) {
  cv::Mat mask = emptyMask();
  mask(cv::Rect(0, 20, 3, 10)).setTo(255);   // left
  mask(cv::Rect(97, 20, 3, 10)).setTo(255);  // right
  mask(cv::Rect(40, 0, 10, 2)).setTo(255);   // top
  mask(cv::Rect(40, 48, 10, 2)).setTo(255);  // bottom
  mask(cv::Rect(1, 40, 3, 3)).setTo(255);    // one pixel off the border: dropped
  dropSmallInteriorRegions(mask, 0.02);
  EXPECT_EQ(cv::countNonZero(mask), 30 + 30 + 20 + 20);
  EXPECT_EQ(marked(mask, cv::Rect(1, 40, 3, 3)), 0);
}

TEST(SmallRegions, ASmallRegionMostlyOnSeenMovingPixelsIsKept) {
  cv::Mat mask = emptyMask();
  cv::Mat keep = emptyMask();
  mask(cv::Rect(10, 10, 9, 11)).setTo(255);  // 99 pixels, 54 of them kept: stays
  keep(cv::Rect(10, 10, 9, 6)).setTo(255);
  mask(cv::Rect(40, 10, 9, 11)).setTo(255);  // 99 pixels, 45 of them kept: dropped
  keep(cv::Rect(40, 10, 9, 5)).setTo(255);
  keep(cv::Rect(70, 10, 9, 9)).setTo(255);  // kept pixels mark nothing themselves
  dropSmallInteriorRegions(mask, 0.02, keep);
  EXPECT_EQ(marked(mask, cv::Rect(10, 10, 9, 11)), 99);
  EXPECT_EQ(marked(mask, cv::Rect(40, 10, 9, 11)), 0);
  EXPECT_EQ(cv::countNonZero(mask), 99);
  cv::Mat small(25, 50, CV_8U, cv::Scalar(0));
  EXPECT_THROW(dropSmallInteriorRegions(mask, 0.02, small), InputError);
}

// Five clusters in a row of 20 x 10 pixels each, with the evidence seenMovingClusters reads.
struct FiveClusters {
  ClusterGraph graph;
  ResidualImages residuals;
  DynamicScores scores;
};

FiveClusters fiveClusters() {
  FiveClusters f;
  f.graph.num_clusters = 5;
  f.graph.labels = cv::Mat(10, 100, CV_32S);
  for (int u = 0; u < 100; ++u) f.graph.labels.col(u).setTo(u / 20);
  f.graph.labels(cv::Rect(0, 0, 20, 2)).setTo(-1);  // pixels without a cluster
  //                         moves, flow residual, share of its pixels agreeing with the map
  // cluster 0: a mover        yes     5 px         0
  // cluster 1: slow           yes     2 px         0
  // cluster 2: not moving     no      6 px         0
  // cluster 3: on the map     yes     6 px         0.5
  // cluster 4: no map there   yes     6 px         none
  f.scores.moving = {1, 1, 0, 1, 1};
  const float flow_px[5] = {5, 2, 6, 6, 6};
  f.residuals.r_F = cv::Mat(10, 100, CV_32F);
  f.residuals.a_M = cv::Mat(10, 100, CV_32F, cv::Scalar(0));
  for (int u = 0; u < 100; ++u) f.residuals.r_F.col(u).setTo(flow_px[u / 20]);
  f.residuals.a_M(cv::Rect(60, 0, 20, 5)).setTo(1);
  f.residuals.a_M(cv::Rect(80, 0, 20, 10)).setTo(std::numeric_limits<float>::quiet_NaN());
  return f;
}

TEST(SmallRegions, SeenMovingAreTheMovingClustersWithAFlowOfTheirOwnOffTheMap) {
  const FiveClusters f = fiveClusters();
  const cv::Mat seen = seenMovingClusters(f.graph, f.residuals, f.scores, 4.0, 0.1);
  ASSERT_EQ(seen.type(), CV_8UC1);
  ASSERT_EQ(seen.size(), f.graph.labels.size());
  EXPECT_EQ(marked(seen, cv::Rect(0, 2, 20, 8)), 160);  // cluster 0's pixels
  EXPECT_EQ(marked(seen, cv::Rect(0, 0, 20, 2)), 0);    // no cluster
  EXPECT_EQ(marked(seen, cv::Rect(20, 0, 60, 10)), 0);  // clusters 1-3
  EXPECT_EQ(marked(seen, cv::Rect(80, 0, 20, 10)), 200);
  EXPECT_EQ(cv::countNonZero(seenMovingClusters(f.graph, f.residuals, f.scores, 0.0, 0.1)), 0);
  EXPECT_EQ(cv::countNonZero(seenMovingClusters(f.graph, f.residuals, f.scores, 4.0, 0.6)), 360 + 200);
  DynamicScores wrong = f.scores;
  wrong.moving.pop_back();
  EXPECT_THROW(seenMovingClusters(f.graph, f.residuals, wrong, 4.0, 0.1), InputError);
}

TEST(SmallRegions, ShareZeroKeepsEverythingAndBadInputIsRefused) {
  cv::Mat mask = emptyMask();
  mask.at<uchar>(25, 50) = 255;
  dropSmallInteriorRegions(mask, 0);
  EXPECT_EQ(cv::countNonZero(mask), 1);
  EXPECT_THROW(dropSmallInteriorRegions(mask, 1.0), InputError);
  EXPECT_THROW(dropSmallInteriorRegions(mask, -0.1), InputError);
  cv::Mat wrong(50, 100, CV_32F, cv::Scalar(0));
  EXPECT_THROW(dropSmallInteriorRegions(wrong, 0.02), InputError);
  cv::Mat empty;
  EXPECT_THROW(dropSmallInteriorRegions(empty, 0.02), InputError);
}

}  // namespace
}  // namespace ff
