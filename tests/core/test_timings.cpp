#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "flowfusion/core/error.h"
#include "flowfusion/core/timings.h"
#include "testing/test_util.h"

namespace ff {
namespace {

TEST(Median, OddEvenAndEmpty) {
  EXPECT_EQ(median({3, 1, 2}), 2);
  EXPECT_EQ(median({4, 1, 3, 2}), 2.5);
  EXPECT_TRUE(std::isnan(median({})));
  EXPECT_EQ(mean({1, 2, 6}), 3);
}

TEST(Timings, PerStageMediansMeansAndCsv) {
  Timings timings;
  timings.beginFrame(1.0);
  timings.add("flow", 10);
  timings.add("odometry", 4);
  timings.add("odometry", 1);  // a stage timed twice in a frame sums
  timings.beginFrame(2.0);
  timings.add("flow", 20);
  timings.add("odometry", 7);
  timings.beginFrame(3.0);
  timings.add("flow", 40);
  timings.add("fusion", 3);  // a stage first seen later
  ASSERT_EQ(timings.frames(), 3u);
  EXPECT_EQ(timings.stages(), (std::vector<std::string>{"flow", "odometry", "fusion"}));
  EXPECT_EQ(timings.medianMs("flow"), 20);
  EXPECT_NEAR(timings.meanMs("flow"), 70.0 / 3, 1e-12);
  EXPECT_EQ(timings.medianMs("odometry"), 6);
  EXPECT_EQ(timings.samples("fusion").size(), 1u);
  EXPECT_EQ(timings.toCsv(),
            "timestamp,flow,odometry,fusion\n"
            "1.000000,10.0000,5.0000,\n"
            "2.000000,20.0000,7.0000,\n"
            "3.000000,40.0000,,3.0000\n");
  const auto j = timings.toJson();
  EXPECT_EQ(j["stages"]["odometry"]["frames"], 2);
  EXPECT_EQ(j["stages"]["flow"]["median_ms"], 20.0);
  EXPECT_EQ(j["frames"][1]["odometry"], 7.0);
  EXPECT_FALSE(j["frames"][2].contains("odometry"));

  ff::testing::TempDir dir;
  const auto path = (dir.path() / "timings.csv").string();
  timings.writeCsv(path);
  std::ifstream in(path);
  std::stringstream content;
  content << in.rdbuf();
  EXPECT_EQ(content.str(), timings.toCsv());
  EXPECT_THROW(timings.writeCsv((dir.path() / "no" / "such" / "dir.csv").string()), InputError);
}

TEST(StageTimer, RecordsOnceIntoTheOpenFrame) {
  Timings timings;
  {
    StageTimer timer(timings, "work");
    const double ms = timer.stop();
    EXPECT_GE(ms, 0);
  }
  { StageTimer timer(timings, "work"); }
  ASSERT_EQ(timings.frames(), 1u);
  EXPECT_EQ(timings.samples("work").size(), 1u);  // both summed into the implicit frame
}

}  // namespace
}  // namespace ff
