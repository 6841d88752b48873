#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "flowfusion/core/error.h"
#include "flowfusion/segmentation/cluster_log.h"

namespace ff {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// A 6 x 4 image: cluster 0 the left 3 columns, cluster 1 the right 3, the top right pixel without
// a cluster (no depth).
ClusterGraph twoClusters() {
  ClusterGraph g;
  g.labels = cv::Mat(4, 6, CV_32S, cv::Scalar(0));
  g.labels(cv::Rect(3, 0, 3, 4)).setTo(1);
  g.labels.at<int>(0, 5) = -1;
  g.num_clusters = 2;
  g.edges = {{0, 1}};
  g.sizes = {12, 11};
  g.mean_depth = {1.5f, 2.5f};
  g.centroids = {Eigen::Vector3f::Zero(), Eigen::Vector3f::Zero()};
  return g;
}

DynamicScores scoresOf(std::vector<float> delta, std::vector<float> b, std::vector<char> moving) {
  DynamicScores s;
  s.delta = std::move(delta);
  s.b = std::move(b);
  s.moving = std::move(moving);
  return s;
}

cv::Mat image(float left, float right) {
  cv::Mat m(4, 6, CV_32F, cv::Scalar(left));
  m(cv::Rect(3, 0, 3, 4)).setTo(right);
  return m;
}

TEST(ClusterLog, EachClusterGetsTheMeansOfItsOwnFiniteResidualsAndItsScore) {
  const ClusterGraph g = twoClusters();
  ResidualImages res;
  res.r_I = image(0.1f, 0.3f);
  res.r_F = image(2.0f, kNaN);  // cluster 1 has no flow residual
  res.r_F.at<float>(0, 0) = kNaN;
  res.r_F.at<float>(1, 0) = 8.0f;  // cluster 0: (10 x 2 + 8) / 11
  res.r_D = image(-0.02f, 0.04f);  // magnitudes
  res.prior = image(0.9f, 0.1f);
  // r_M, a_M and the memory absent: NaN for every cluster.
  const ClusterLog log = clusterLog(g, res, scoresOf({0.7f, kNaN}, {0.8f, 0.1f}, {1, 0}));
  ASSERT_EQ(log.clusters.size(), 2u);
  const ClusterRecord& a = log.clusters[0];
  const ClusterRecord& b = log.clusters[1];
  EXPECT_EQ(a.pixels, 12);
  EXPECT_DOUBLE_EQ(a.u_px, 1.0);
  EXPECT_DOUBLE_EQ(a.v_px, 1.5);
  EXPECT_DOUBLE_EQ(b.u_px, (3 + 4 + 5) * 3.0 / 11 + (3 + 4) / 11.0);
  EXPECT_NEAR(a.r_I, 0.1, 1e-6);
  EXPECT_NEAR(b.r_I, 0.3, 1e-6);
  EXPECT_NEAR(a.r_F_px, 28.0 / 11, 1e-6);
  EXPECT_TRUE(std::isnan(b.r_F_px));
  EXPECT_NEAR(a.r_D_m, 0.02, 1e-6);
  EXPECT_NEAR(b.prior, 0.1, 1e-6);
  EXPECT_TRUE(std::isnan(a.r_M_m) && std::isnan(a.a_M) && std::isnan(a.memory));
  EXPECT_DOUBLE_EQ(a.depth_m, 1.5);
  EXPECT_NEAR(a.b, 0.8, 1e-6);
  EXPECT_TRUE(a.moving);
  EXPECT_FALSE(b.moving);
  EXPECT_TRUE(std::isnan(b.delta));
  EXPECT_EQ(log.labels.at<int>(0, 5), -1);
}

TEST(ClusterLog, TheCsvHasOneRowPerClusterAndWritesMissingValuesAsNan) {
  const ClusterGraph g = twoClusters();
  ResidualImages res;
  res.r_F = image(2.0f, kNaN);
  const std::string csv = clusterLogCsv(clusterLog(g, res, scoresOf({0.7f, kNaN}, {0.8f, 0.1f}, {1, 0})));
  std::istringstream lines(csv);
  std::string header, first, second, extra;
  std::getline(lines, header);
  std::getline(lines, first);
  std::getline(lines, second);
  EXPECT_FALSE(std::getline(lines, extra));
  EXPECT_EQ(header, "cluster,pixels,u_px,v_px,depth_m,r_I,r_D_m,r_F_px,r_M_m,a_M,prior,memory,delta,b,moving");
  EXPECT_EQ(first, "0,12,1.0,1.5,1.5000,nan,nan,2.0000,nan,nan,nan,nan,0.7000,0.8000,1");
  EXPECT_EQ(second.substr(0, 5), "1,11,");
  EXPECT_NE(second.find(",nan,0.1000,0"), std::string::npos) << second;
}

TEST(ClusterLog, ScoresOfAnotherGraphAreRefused) {
  const ClusterGraph g = twoClusters();
  EXPECT_THROW(clusterLog(g, {}, scoresOf({0.1f}, {0.1f}, {0})), InputError);
  ResidualImages wrong_size;
  wrong_size.r_I = cv::Mat(3, 3, CV_32F, cv::Scalar(0));
  EXPECT_THROW(clusterLog(g, wrong_size, scoresOf({0.1f, 0.1f}, {0.1f, 0.1f}, {0, 0})), InputError);
}

}  // namespace
}  // namespace ff
