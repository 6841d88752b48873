#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "flowfusion/core/error.h"
#include "flowfusion/eval/trajectory_metrics.h"

namespace ff::eval {
namespace {

SE3 rotZ(double rad) {
  SE3 T = SE3::Identity();
  T.linear() = Eigen::AngleAxisd(rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return T;
}

// A smooth hand-held-like motion: n poses every dt_s seconds, translating and rotating.
Trajectory wobblyTrajectory(size_t n, double dt_s, double t0 = 1000.0) {
  Trajectory traj;
  for (size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) * dt_s;
    SE3 T = SE3::Identity();
    T.linear() = (Eigen::AngleAxisd(0.3 * std::sin(0.7 * t), Eigen::Vector3d::UnitY()) *
                  Eigen::AngleAxisd(0.2 * std::cos(0.4 * t), Eigen::Vector3d::UnitX()))
                     .toRotationMatrix();
    T.translation() = Eigen::Vector3d(0.5 * std::sin(0.3 * t), 0.2 * t, 0.1 * std::cos(0.9 * t));
    traj.push_back({t0 + t, T});
  }
  return traj;
}

TEST(ErrorStats, MatchesNumpyConventions) {
  const auto s = errorStats({1, 2, 3, 4});
  EXPECT_DOUBLE_EQ(s.mean, 2.5);
  EXPECT_DOUBLE_EQ(s.median, 2.5);
  EXPECT_DOUBLE_EQ(s.rmse, std::sqrt(30.0 / 4));
  EXPECT_DOUBLE_EQ(s.std, std::sqrt(1.25));  // population std, as numpy.std
  EXPECT_DOUBLE_EQ(s.min, 1);
  EXPECT_DOUBLE_EQ(s.max, 4);
}

TEST(AssociateStamps, GreedyBySmallestDifferenceStrictLimit) {
  // 0.01 is closer to 0.009 than 0.0 is, so it wins; 0.0 then has nothing left.
  auto m = associateStamps({0.0, 0.01}, {0.009}, 0.02);
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(m[0], std::make_pair(size_t{1}, size_t{0}));
  // associate.py keeps only differences strictly below the limit.
  EXPECT_TRUE(associateStamps({0.0}, {0.5}, 0.5).empty());
  EXPECT_EQ(associateStamps({0.0}, {0.25}, 0.5).size(), 1u);
}

TEST(AssociateStamps, JitteredStampsPairWithTheirOriginals) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.008, 0.008);
  std::vector<double> a, b;
  for (int k = 0; k < 200; ++k) {
    a.push_back(10 + 0.033 * k);
    b.push_back(a.back() + jitter(rng));
  }
  b.erase(b.begin() + 50);  // a dropped frame leaves a[50] unmatched (neighbours are 33 ms away)
  const auto m = associateStamps(a, b, 0.02);
  ASSERT_EQ(m.size(), 199u);
  for (const auto& [i, j] : m) EXPECT_EQ(i, j < 50 ? j : j + 1);
}

TEST(Ate, IdenticalTrajectoriesGiveZero) {
  const auto gt = wobblyTrajectory(200, 0.03);
  const auto r = computeAte(gt, gt);
  EXPECT_EQ(r.matched_poses, 200u);
  EXPECT_LT(r.translation_m.rmse, 1e-12);
  EXPECT_LT(r.translation_m.max, 1e-12);
}

TEST(Ate, RigidlyMovedCopyAlignsToZero) {
  const auto gt = wobblyTrajectory(200, 0.03);
  SE3 T_other_world = rotZ(1.1) * SE3(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitX()));
  T_other_world.translation() = Eigen::Vector3d(3, -2, 0.5);
  Trajectory est = gt;
  for (auto& p : est) p.T_world_cam = T_other_world * p.T_world_cam;
  const auto r = computeAte(gt, est);
  EXPECT_LT(r.translation_m.rmse, 1e-9);
  // The alignment found is the inverse of the applied motion.
  EXPECT_TRUE((r.T_gt_est * T_other_world).matrix().isIdentity(1e-9));
  const auto rpe = computeRpe(gt, est);
  EXPECT_LT(rpe.translation_m.rmse, 1e-9);
  EXPECT_LT(rpe.rotation_deg.rmse, 1e-5);  // arccos of a trace near 3 resolves ~1e-6 deg
}

TEST(Ate, WithoutAlignmentAMovedCopyKeepsItsOffset) {
  const auto gt = wobblyTrajectory(200, 0.03);
  Trajectory est = gt;
  for (auto& p : est) p.T_world_cam.translation() += Eigen::Vector3d(0.03, 0.0, -0.04);  // 5 cm away
  const auto r = computeAte(gt, est, 0.02, "gt", "est", AteAlignment::None);
  EXPECT_NEAR(r.translation_m.rmse, 0.05, 1e-12);
  EXPECT_NEAR(r.translation_m.min, 0.05, 1e-12);
  EXPECT_TRUE(r.T_gt_est.matrix().isIdentity(0));
  EXPECT_LT(computeAte(gt, est).translation_m.rmse, 1e-9);  // the alignment takes it away
  // One pose is enough to compare without aligning.
  const Trajectory one(est.begin(), est.begin() + 1);
  EXPECT_EQ(computeAte(gt, one, 0.02, "gt", "est", AteAlignment::None).matched_poses, 1u);
  EXPECT_THROW(computeAte(gt, one), InputError);
}

TEST(Ate, GaussianPositionNoiseGivesSigmaSqrt3) {
  const double sigma = 0.01;
  const auto gt = wobblyTrajectory(5000, 0.03);
  Trajectory est = gt;
  std::mt19937 rng(42);
  std::normal_distribution<double> noise(0.0, sigma);
  for (auto& p : est) p.T_world_cam.translation() += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
  const auto r = computeAte(gt, est);
  // RMSE of |n| for n ~ N(0, sigma^2 I3) is sigma*sqrt(3); 5000 samples give ~1% spread.
  EXPECT_NEAR(r.translation_m.rmse, sigma * std::sqrt(3.0), 0.03 * sigma * std::sqrt(3.0));
  // The mean of a chi distribution with 3 dof: 2*sqrt(2/pi) sigma.
  EXPECT_NEAR(r.translation_m.mean, 2 * std::sqrt(2 / M_PI) * sigma, 0.03 * sigma);
}

// A camera stamped 20 ms late (on arrival): every 33rd pose of a 1 kHz ground truth, stamped 20 ms
// after its time. Its ATE and RPE come back to zero with --offset -0.02, as the TUM scripts'.
TEST(Ate, AnOffsetTakesACameraStampedLateBackToTheGroundTruthsClock) {
  const Trajectory gt = wobblyTrajectory(6000, 0.001);
  Trajectory late;
  for (size_t k = 0; k < gt.size(); k += 33) late.push_back({gt[k].timestamp + 0.02, gt[k].T_world_cam});
  EXPECT_GT(computeAte(gt, late).translation_m.rmse, 5e-4);
  const Trajectory shifted = withTimeOffset(late, -0.02);
  ASSERT_EQ(shifted.size(), late.size());
  EXPECT_NEAR(shifted[5].timestamp, gt[5 * 33].timestamp, 1e-9);
  const AteResult ate = computeAte(gt, shifted);
  EXPECT_EQ(ate.matched_poses, late.size());
  EXPECT_LT(ate.translation_m.rmse, 1e-9);
  EXPECT_LT(computeRpe(gt, shifted, 1.0).translation_m.rmse, 1e-9);
  EXPECT_THROW(withTimeOffset(late, std::numeric_limits<double>::quiet_NaN()), InputError);
}

TEST(Ate, TooFewMatchesOrNoOverlapIsInputError) {
  const auto gt = wobblyTrajectory(100, 0.03, 1000);
  const auto late = wobblyTrajectory(100, 0.03, 2000);
  try {
    computeAte(gt, late, 0.02, "gt.txt", "est.txt");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("gt.txt"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("est.txt"), std::string::npos);
  }
  const Trajectory two(gt.begin(), gt.begin() + 2);
  EXPECT_THROW(computeAte(gt, two), InputError);
  EXPECT_THROW(computeAte(gt, gt, 0.0), InputError);
}

TEST(Rpe, IdenticalTrajectoriesGiveZeroAndScriptPairCount) {
  const auto gt = wobblyTrajectory(101, 0.1);  // 10 s
  const auto r = computeRpe(gt, gt, 1.0);
  // Pairs (i, i+10) for i = 0..89: the pair ending at the last pose (i = 90) is skipped by the
  // script, as are later poses whose closest partner is the last pose.
  EXPECT_EQ(r.pairs, 90u);
  EXPECT_LT(r.translation_m.max, 1e-12);
  EXPECT_LT(r.rotation_deg.max, 1e-5);
}

TEST(Rpe, ConstantTranslationalDriftGivesDriftRate) {
  // Static-orientation camera; the estimate drifts at a constant world velocity.
  const Eigen::Vector3d drift_m_per_s(0.03, -0.04, 0.0);  // 0.05 m/s
  Trajectory gt, est;
  for (int k = 0; k <= 300; ++k) {
    const double t = 0.05 * k;
    SE3 T = SE3::Identity();
    T.translation() = Eigen::Vector3d(std::sin(t), 0.1 * t, 0.0);
    gt.push_back({t, T});
    T.translation() += drift_m_per_s * t;
    est.push_back({t, T});
  }
  const auto r1 = computeRpe(gt, est, 1.0);
  EXPECT_NEAR(r1.translation_m.rmse, 0.05, 1e-9);
  EXPECT_NEAR(r1.translation_m.min, 0.05, 1e-9);
  EXPECT_NEAR(r1.translation_rmse_m_per_s, 0.05, 1e-9);
  const auto r2 = computeRpe(gt, est, 2.0);
  EXPECT_NEAR(r2.translation_m.rmse, 0.10, 1e-9);  // metres over 2 s, as the script prints
  EXPECT_NEAR(r2.translation_rmse_m_per_s, 0.05, 1e-9);
}

TEST(Rpe, ConstantYawDriftGivesRotationRate) {
  const double drift_deg_per_s = 2.0;
  Trajectory gt, est;
  for (int k = 0; k <= 200; ++k) {
    const double t = 0.05 * k;
    // A camera turning on the spot, so the rotation error alone is measured.
    gt.push_back({t, SE3::Identity()});
    est.push_back({t, rotZ(drift_deg_per_s * t * M_PI / 180)});
  }
  const auto r = computeRpe(gt, est, 1.0);
  EXPECT_NEAR(r.rotation_deg.rmse, 2.0, 1e-6);
  EXPECT_NEAR(r.rotation_rmse_deg_per_s, 2.0, 1e-6);
  EXPECT_LT(r.translation_m.max, 1e-12);
}

TEST(Rpe, NoOverlapOrTooShortIsInputError) {
  const auto gt = wobblyTrajectory(100, 0.03, 1000);
  const auto late = wobblyTrajectory(100, 0.03, 2000);
  try {
    computeRpe(gt, late, 1.0, "gt.txt", "est.txt");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("do not overlap"), std::string::npos) << e.what();
  }
  const auto shortEst = wobblyTrajectory(20, 0.03, 1000);  // 0.6 s: no pair 1 s apart
  EXPECT_THROW(computeRpe(gt, shortEst, 1.0), InputError);
  EXPECT_THROW(computeRpe(gt, gt, -1.0), InputError);
}

TEST(Rpe, DeltaBeyondTheEstimateOrNotFiniteIsInputError) {
  const auto gt = wobblyTrajectory(100, 0.03, 1000);  // 2.97 s
  try {
    computeRpe(gt, gt, 1e300, "gt.txt", "est.txt");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--delta: 1e+300 s"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("not shorter than est.txt (2.970000 s"), std::string::npos) << e.what();
  }
  EXPECT_THROW(computeRpe(gt, gt, std::nan("")), InputError);
  EXPECT_THROW(computeRpe(gt, gt, INFINITY), InputError);
  EXPECT_NO_THROW(computeRpe(gt, gt, 2.5));
}

// Many estimated poses that all map onto few ground-truth poses: the overlap test counts the
// distinct round trips with flags (it searched a growing list, quadratic in the poses).
TEST(Rpe, DenseEstimateOverSparseGroundTruth) {
  const auto gt = wobblyTrajectory(50, 0.2, 1000);
  const auto est = wobblyTrajectory(20000, 0.0005, 1000);
  const auto r = computeRpe(gt, est, 1.0);
  EXPECT_GT(r.pairs, 15000u);
}

TEST(Rpe, EstimateAtDifferentRateUsesClosestGroundTruth) {
  const auto gt = wobblyTrajectory(1001, 0.01);  // 100 Hz ground truth, like the TUM mocap
  Trajectory est;
  for (size_t k = 0; k < gt.size(); k += 3) est.push_back({gt[k].timestamp + 0.002, gt[k].T_world_cam});
  const auto r = computeRpe(gt, est, 1.0);
  EXPECT_GT(r.pairs, 200u);
  // Stamps 2 ms off on a 0.2 m/s path: errors stay at the millimetre level.
  EXPECT_LT(r.translation_m.max, 1e-3);
}

}  // namespace
}  // namespace ff::eval
