// TUM trajectory files: round trip at TUM-sized timestamps, and the errors each defect must give.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <string>

#include "flowfusion/core/error.h"
#include "flowfusion/io/trajectory_io.h"
#include "testing/test_util.h"

namespace ff {
namespace {

std::string writeFile(const testing::TempDir& tmp, const std::string& name, const std::string& text) {
  const std::string p = (tmp.path() / name).string();
  std::ofstream(p) << text;
  return p;
}

void expectInputError(const std::string& path, const std::string& needle) {
  try {
    readTrajectory(path);
    ADD_FAILURE() << path << ": no InputError";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find(needle), std::string::npos) << "'" << msg << "' lacks '" << needle << "'";
  }
}

TEST(TrajectoryIo, RoundTrip) {
  testing::TempDir tmp;
  Trajectory traj;
  for (int i = 0; i < 5; ++i) {
    Vector6d xi;
    xi << 0.1 * i, -0.2 * i, 1.5, 0.05 * i, 0.3 - 0.1 * i, 0.02 * i;
    // Real TUM timestamps are ~1.3e9 s: microseconds must survive the round trip.
    traj.push_back({1305031102.175304 + 0.033333 * i, expSE3(xi)});
  }
  const std::string p = (tmp.path() / "traj.txt").string();
  writeTrajectory(p, traj);
  const Trajectory back = readTrajectory(p);
  ASSERT_EQ(back.size(), traj.size());
  for (size_t i = 0; i < traj.size(); ++i) {
    EXPECT_NEAR(back[i].timestamp, traj[i].timestamp, 1e-6);
    const SE3 d = back[i].T_world_cam * traj[i].T_world_cam.inverse();
    EXPECT_LT(translationNorm(d), 1e-6);
    EXPECT_LT(rotationAngleDeg(d), 1e-4);
  }
}

TEST(TrajectoryIo, CommentsAndBlankLinesAreSkipped) {
  testing::TempDir tmp;
  const auto p = writeFile(tmp, "t.txt", "# header\n\n1.0 1 2 3 0 0 0 1\n  # indented comment\n2.0 1 2 3 0 0 0 1\n");
  const Trajectory t = readTrajectory(p);
  ASSERT_EQ(t.size(), 2u);
  EXPECT_DOUBLE_EQ(t[0].T_world_cam.translation().y(), 2.0);
}

TEST(TrajectoryIo, BadFiles) {
  testing::TempDir tmp;
  expectInputError(writeFile(tmp, "malformed.txt", "1.0 1 2 3 0 0 0 1\n2.0 1 2 3 0 0\n"), ":2");
  expectInputError(writeFile(tmp, "words.txt", "1.0 a b c 0 0 0 1\n"), ":1");
  expectInputError(writeFile(tmp, "quat.txt", "1.0 1 2 3 0 0 0 2\n"), "unit");
  expectInputError(writeFile(tmp, "zeroquat.txt", "1.0 1 2 3 0 0 0 0\n"), "unit");
  expectInputError(writeFile(tmp, "order.txt", "2.0 1 2 3 0 0 0 1\n1.0 1 2 3 0 0 0 1\n"), ":2");
  expectInputError(writeFile(tmp, "dup.txt", "1.0 1 2 3 0 0 0 1\n1.0 1 2 3 0 0 0 1\n"), ":2");
  expectInputError(writeFile(tmp, "empty.txt", "# nothing\n"), "no poses");
  expectInputError((tmp.path() / "missing.txt").string(), "cannot open");
}

TEST(TrajectoryIo, InterpolatePose) {
  Trajectory traj;
  SE3 a = SE3::Identity(), b = SE3::Identity();
  b.translation() << 1, 0, 0;
  traj.push_back({1.0, a});
  traj.push_back({1.05, b});
  traj.push_back({2.0, b});
  SE3 out;
  ASSERT_TRUE(interpolatePose(traj, 1.025, out));
  EXPECT_NEAR(out.translation().x(), 0.5, 1e-9);
  EXPECT_FALSE(interpolatePose(traj, 0.5, out));
  EXPECT_FALSE(interpolatePose(traj, 1.5, out));  // 0.95 s gap > 0.1 s
  ASSERT_TRUE(interpolatePose(traj, 2.0, out));
  EXPECT_NEAR(out.translation().x(), 1.0, 1e-12);
}

}  // namespace
}  // namespace ff
