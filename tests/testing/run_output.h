#pragma once
// What a whole run gives, collected by a sink, for tests that compare two runs of the same frames
// from different sources (a folder, a ROS 1 bag, a ROS 2 bag): poses and masks equal to 1e-9.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <string>
#include <utility>
#include <vector>

#include "flowfusion/pipeline/run.h"

namespace ff::testing {

// Poses and masks of a whole run.
struct RunOutput : ResultSink {
  std::vector<std::pair<double, SE3>> poses;
  std::vector<cv::Mat> masks;
  void frame(const RgbdFrame&, const FrameResult& r) override {
    poses.emplace_back(r.timestamp, r.T_world_cam);
    masks.push_back(r.dynamic_mask.clone());
  }
};

inline RunOutput runOn(FrameSource& source) {
  RunOutput out;
  runSequence(source, SystemConfig{}, {&out});
  return out;
}

inline void expectSameRun(const RunOutput& a, const RunOutput& b, const std::string& what) {
  ASSERT_EQ(a.poses.size(), b.poses.size()) << what;
  for (size_t i = 0; i < a.poses.size(); ++i) {
    EXPECT_NEAR(a.poses[i].first, b.poses[i].first, 1e-9) << what;
    EXPECT_LT((a.poses[i].second.matrix() - b.poses[i].second.matrix()).cwiseAbs().maxCoeff(), 1e-9) << what;
    EXPECT_EQ(cv::norm(a.masks[i], b.masks[i], cv::NORM_INF), 0) << what << " frame " << i;
  }
}

}  // namespace ff::testing
