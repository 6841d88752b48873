#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "flowfusion/core/error.h"
#include "flowfusion/eval/cluster_truth.h"
#include "testing/test_util.h"

namespace ff::eval {
namespace {

namespace fs = std::filesystem;

// One frame at t = 1.0: a 20 x 10 image in four clusters of 5 columns each. The truth marks
// clusters 0 and 1 wholly and 2 on 2 of its 5 columns; the log scores 0 and 2 dynamic, 1 and 3 not.
struct OneFrame {
  ff::testing::TempDir dir;
  fs::path truth = dir.path() / "truth", logs = dir.path() / "clusters";
  OneFrame() {
    fs::create_directories(truth);
    fs::create_directories(logs);
    cv::Mat mask(10, 20, CV_8U, cv::Scalar(0));
    mask(cv::Rect(0, 0, 12, 10)).setTo(255);
    cv::imwrite((truth / "1.000000.png").string(), mask);
    cv::Mat labels(10, 20, CV_16U);
    for (int c = 0; c < 4; ++c) labels(cv::Rect(5 * c, 0, 5, 10)).setTo(c + 1);
    cv::imwrite((logs / "1.004000.png").string(), labels);
    std::ofstream(logs / "1.004000.csv") << "cluster,pixels,b,moving\n0,50,0.9,1\n1,50,0.2,0\n2,50,0.7,0\n3,50,0.1,0\n";
  }
};

TEST(ClusterTruth, EachClusterIsJudgedByItsShareOfTheTruthAndItsScore) {
  OneFrame f;
  const ClusterTruth t = clusterTruth(f.truth.string(), f.logs.string());
  ASSERT_EQ(t.rows.size(), 4u);
  EXPECT_EQ(t.header, "cluster,pixels,b,moving");
  EXPECT_DOUBLE_EQ(t.rows[0].truth_share, 1.0);
  EXPECT_EQ(t.rows[0].verdict, ClusterVerdict::kHit);
  EXPECT_EQ(t.rows[1].verdict, ClusterVerdict::kMissed);
  EXPECT_DOUBLE_EQ(t.rows[2].truth_share, 0.4);
  EXPECT_EQ(t.rows[2].verdict, ClusterVerdict::kFalse);
  EXPECT_EQ(t.rows[3].verdict, ClusterVerdict::kStatic);
  EXPECT_EQ(t.rows[0].frame, 0);
  const std::string csv = clusterTruthCsv(t, 0, 10, false);
  EXPECT_EQ(csv,
            "frame,timestamp,cluster,pixels,b,moving,truth_share,verdict\n"
            "0,1.004000,0,50,0.9,1,1.000,hit\n"
            "0,1.004000,1,50,0.2,0,1.000,missed\n"
            "0,1.004000,2,50,0.7,0,0.400,false\n");
  EXPECT_NE(clusterTruthCsv(t, 0, 10, true).find("3,50,0.1,0,0.000,static"), std::string::npos);
  EXPECT_EQ(clusterTruthCsv(t, 1, 10, true), "frame,timestamp,cluster,pixels,b,moving,truth_share,verdict\n");
}

TEST(ClusterTruth, AMissingLabelImageOrABadRowIsNamed) {
  OneFrame f;
  std::ofstream(f.logs / "1.004000.csv", std::ios::app) << "x,50,0.5,0\n";
  EXPECT_NE(ff::testing::inputErrorOf([&] { clusterTruth(f.truth.string(), f.logs.string()); }).find("1.004000.csv:6"),
            std::string::npos);
  fs::remove(f.logs / "1.004000.png");
  EXPECT_NE(ff::testing::inputErrorOf([&] { clusterTruth(f.truth.string(), f.logs.string()); }).find("1.004000.png"),
            std::string::npos);
  EXPECT_THROW(clusterTruth(f.truth.string(), (f.dir.path() / "none").string()), InputError);
  EXPECT_THROW(clusterTruth(f.truth.string(), f.truth.string()), InputError);  // no .csv there
}

}  // namespace
}  // namespace ff::eval
