#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "flowfusion/eval/trajectory_metrics.h"
#include "testing/test_util.h"

namespace ff::eval {
namespace {

using ff::testing::runFlowfusion;

// Ground truth and a noisy, rigidly moved copy written to files, plus the library's answer on
// the files as written (6-7 decimals).
struct TrajectoryFiles {
  ff::testing::TempDir dir;
  std::string gt, est;
  TrajectoryFiles() {
    Trajectory g, e;
    std::mt19937 rng(3);
    std::normal_distribution<double> noise(0.0, 0.005);
    SE3 T_other_world(Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()));
    T_other_world.translation() = Eigen::Vector3d(1, 2, 3);
    for (int k = 0; k < 300; ++k) {
      const double t = 100 + 0.033 * k;
      SE3 T(Eigen::AngleAxisd(0.01 * k, Eigen::Vector3d::UnitY()));
      T.translation() = Eigen::Vector3d(0.3 * std::sin(0.05 * k), 0.002 * k, 0.1);
      g.push_back({t, T});
      SE3 E = T_other_world * T;
      E.translation() += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
      e.push_back({t + 0.004, E});
    }
    gt = (dir.path() / "gt.txt").string();
    est = (dir.path() / "est.txt").string();
    writeTrajectory(gt, g);
    writeTrajectory(est, e);
  }
};

double valueAfter(const std::string& text, const std::string& key) {
  const auto pos = text.find(key + " ");
  if (pos == std::string::npos) return NAN;
  return std::stod(text.substr(pos + key.size() + 1));
}

TEST(CmdEval, AtePrintsTheScriptsLines) {
  TrajectoryFiles f;
  const auto expected = computeAte(readTrajectory(f.gt), readTrajectory(f.est));
  const auto r = runFlowfusion("eval ate " + f.gt + " " + f.est);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(valueAfter(r.output, "compared_pose_pairs"), 300);
  EXPECT_NEAR(valueAfter(r.output, "absolute_translational_error.rmse"), expected.translation_m.rmse, 1e-6);
  EXPECT_NEAR(valueAfter(r.output, "absolute_translational_error.max"), expected.translation_m.max, 1e-6);
  // 5 mm per axis of noise: about 8.7 mm RMSE.
  EXPECT_NEAR(expected.translation_m.rmse, 0.005 * std::sqrt(3.0), 0.001);

  const auto j = runFlowfusion("eval ate --json " + f.gt + " " + f.est);
  ASSERT_EQ(j.status, 0) << j.output;
  const auto parsed = nlohmann::json::parse(j.output);
  EXPECT_NEAR(parsed["translation_m"]["rmse"].get<double>(), expected.translation_m.rmse, 1e-12);
  // 4 ms offsets are within --max-diff 0.02 but not within 0.003.
  EXPECT_EQ(runFlowfusion("eval ate --max-diff 0.003 " + f.gt + " " + f.est).status, 2);
  // --offset moves EST's stamps back onto GT's (as the scripts' --offset); not a number of seconds: refused.
  const auto back = runFlowfusion("eval ate --max-diff 0.003 --offset -0.004 " + f.gt + " " + f.est);
  ASSERT_EQ(back.status, 0) << back.output;
  EXPECT_NEAR(valueAfter(back.output, "absolute_translational_error.rmse"), expected.translation_m.rmse, 1e-6);
  const auto nan = runFlowfusion("eval ate --offset nan " + f.gt + " " + f.est);
  EXPECT_EQ(nan.status, 2);
  EXPECT_NE(nan.output.find("--offset"), std::string::npos) << nan.output;
}

TEST(CmdEval, AteWithoutAlignmentComparesThePosesAsTheyStand) {
  TrajectoryFiles f;
  const auto expected =
      computeAte(readTrajectory(f.gt), readTrajectory(f.est), 0.02, "gt", "est", AteAlignment::None);
  const auto r = runFlowfusion("eval ate --no-align " + f.gt + " " + f.est);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NEAR(valueAfter(r.output, "absolute_translational_error.rmse"), expected.translation_m.rmse, 1e-6);
  // The copy is moved by 0.5 rad and (1, 2, 3) m: metres away unaligned, millimetres aligned.
  EXPECT_GT(expected.translation_m.rmse, 1.0);
}

TEST(CmdEval, RpePrintsErrorsAndRates) {
  TrajectoryFiles f;
  const auto expected = computeRpe(readTrajectory(f.gt), readTrajectory(f.est), 0.5);
  const auto r = runFlowfusion("eval rpe --delta 0.5 " + f.gt + " " + f.est);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(valueAfter(r.output, "compared_pose_pairs"), static_cast<double>(expected.pairs));
  EXPECT_NEAR(valueAfter(r.output, "translational_error.rmse"), expected.translation_m.rmse, 1e-6);
  EXPECT_NEAR(valueAfter(r.output, "translational_error.rmse_per_second"), expected.translation_rmse_m_per_s,
              1e-6);
  EXPECT_NEAR(valueAfter(r.output, "rotational_error.rmse"), expected.rotation_deg.rmse, 1e-6);
}

TEST(CmdEval, BadInputsExitWithStatus2AndNameTheFile) {
  TrajectoryFiles f;
  const std::string missing = (f.dir.path() / "missing.txt").string();
  auto r = runFlowfusion("eval ate " + f.gt + " " + missing);
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("missing.txt"), std::string::npos) << r.output;

  const std::string bad = (f.dir.path() / "bad.txt").string();
  std::ofstream(bad) << "# comment\n1.0 0 0 0 0 0 0 1\n2.0 0 0 zero 0 0 0 1\n";
  r = runFlowfusion("eval rpe " + f.gt + " " + bad);
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("bad.txt:3"), std::string::npos) << r.output;

  const std::string late = (f.dir.path() / "late.txt").string();
  std::ofstream(late) << "5000.0 0 0 0 0 0 0 1\n5001.0 0 0 0 0 0 0 1\n5002.0 0 0 0 0 0 0 1\n";
  r = runFlowfusion("eval rpe " + f.gt + " " + late);
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("late.txt"), std::string::npos) << r.output;
}

TEST(CmdEval, SegPrintsMeanAndPooledScores) {
  ff::testing::TempDir dir;
  const auto gt_dir = dir.path() / "gt", est_dir = dir.path() / "est";
  std::filesystem::create_directories(gt_dir);
  std::filesystem::create_directories(est_dir);
  cv::Mat gt(20, 20, CV_8UC1, cv::Scalar(0)), est(20, 20, CV_8UC1, cv::Scalar(0));
  gt(cv::Rect(0, 0, 10, 10)).setTo(255);
  est(cv::Rect(0, 0, 10, 5)).setTo(255);
  cv::imwrite((gt_dir / "1.000000.png").string(), gt);
  cv::imwrite((est_dir / "1.000000.png").string(), est);
  const auto r = runFlowfusion("eval seg " + gt_dir.string() + " " + est_dir.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NEAR(valueAfter(r.output, "mean_iou"), 0.5, 1e-6);
  EXPECT_NEAR(valueAfter(r.output, "pooled_precision"), 1.0, 1e-6);
  EXPECT_NEAR(valueAfter(r.output, "pooled_recall"), 0.5, 1e-6);
}

TEST(CmdEval, SegSheetShowsTheWorstFramesAndRefusesToOverwrite) {
  namespace fs = std::filesystem;
  ff::testing::TempDir dir;
  const fs::path seq = ff::testing::makeTinySequence(dir.path() / "seq");
  const fs::path gt_dir = seq / "masks", est_dir = dir.path() / "est";
  fs::create_directories(gt_dir);
  fs::create_directories(est_dir);
  // First frame: a large mover half found (IoU 0.5, 768 pixels wrong). Second: a 2x2 px sliver
  // missed (IoU 0, 4 pixels wrong).
  cv::Mat gt1(48, 64, CV_8UC1, cv::Scalar(0)), est1 = gt1.clone(), gt2 = gt1.clone(), est2 = gt1.clone();
  gt1(cv::Rect(0, 0, 32, 48)).setTo(255);
  est1(cv::Rect(0, 0, 16, 48)).setTo(255);
  gt2(cv::Rect(60, 0, 2, 2)).setTo(255);
  cv::imwrite((gt_dir / "1.000000.png").string(), gt1);
  cv::imwrite((est_dir / "1.000000.png").string(), est1);
  cv::imwrite((gt_dir / "1.033333.png").string(), gt2);
  cv::imwrite((est_dir / "1.033333.png").string(), est2);
  const std::string sheet = (dir.path() / "sheet.png").string();
  const std::string args = "eval seg " + gt_dir.string() + " " + est_dir.string() + " --sheet-rows 1 --sheet " + sheet;
  // The comparison column at the first frame's missed half (x = 24 px of 64, scaled by 5).
  const auto comparedPixel = [&] {
    const cv::Mat img = cv::imread(sheet);
    EXPECT_EQ(img.cols, 5 * 320);  // five columns, the 64x48 frames scaled to 320x240
    EXPECT_GT(img.rows, 240);      // one row under the title strip
    EXPECT_LT(img.rows, 2 * 240);
    return img.empty() ? cv::Vec3b() : img.at<cv::Vec3b>(img.rows - 60, 4 * 320 + 120);
  };
  const auto r = runFlowfusion(args);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(comparedPixel(), cv::Vec3b(0, 0, 255));  // the most pixels wrong: the first frame, missed = red
  ASSERT_EQ(runFlowfusion(args + " --overwrite --sheet-by iou").status, 0);
  EXPECT_NE(comparedPixel(), cv::Vec3b(0, 0, 255));  // the lowest IoU: the second frame, static there

  auto again = runFlowfusion(args);
  EXPECT_EQ(again.status, 2);
  EXPECT_NE(again.output.find("--overwrite"), std::string::npos) << again.output;
  again = runFlowfusion("eval seg " + gt_dir.string() + " " + est_dir.string() + " --sheet " +
                        (est_dir / "sheet.png").string());
  EXPECT_EQ(again.status, 2);
  EXPECT_NE(again.output.find("among the masks"), std::string::npos) << again.output;
  EXPECT_FALSE(fs::exists(est_dir / "sheet.png"));
}

// ASCII PLY of a 10x10 grid of points 1 cm apart on z = 0, the first `lifted` of them 10 cm up.
std::string writeGridPly(const std::filesystem::path& path, int lifted) {
  std::ofstream f(path);
  f << "ply\nformat ascii 1.0\nelement vertex 100\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  for (int k = 0; k < 100; ++k) f << 0.01 * (k % 10) << " " << 0.01 * (k / 10) << " " << (k < lifted ? 0.1 : 0.0) << "\n";
  return path.string();
}

TEST(CmdEval, ClustersJoinsARunsClusterLogWithTheTrueMasks) {
  namespace fs = std::filesystem;
  ff::testing::TempDir dir;
  const fs::path seq = dir.path() / "seq", out = dir.path() / "out", plain = dir.path() / "plain";
  ASSERT_EQ(runFlowfusion("synth " + seq.string() + " --width 160 --height 120 --frames 12 --seed 5 --objects 2").status,
            0);
  ASSERT_EQ(runFlowfusion("run " + seq.string() + " --out " + out.string() + " --no-map --quiet --cluster-log").status,
            0);
  ASSERT_EQ(runFlowfusion("run " + seq.string() + " --out " + plain.string() + " --no-map --quiet").status, 0);
  // Every frame after the first is scored and logged; the log changes nothing else.
  int logs = 0;
  for (const auto& e : fs::directory_iterator(out / "clusters")) logs += e.path().extension() == ".csv";
  EXPECT_EQ(logs, 11);
  EXPECT_FALSE(fs::exists(plain / "clusters"));
  std::ifstream a(out / "trajectory.txt"), b(plain / "trajectory.txt");
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(a), {}), std::string(std::istreambuf_iterator<char>(b), {}));

  const auto r = runFlowfusion("eval clusters " + (seq / "masks").string() + " " + (out / "clusters").string());
  ASSERT_EQ(r.status, 0) << r.output;
  std::istringstream lines(r.output);
  std::string line;
  std::getline(lines, line);
  EXPECT_EQ(line, "frame,timestamp,cluster,pixels,u_px,v_px,depth_m,r_I,r_D_m,r_F_px,r_M_m,a_M,prior,memory,delta,b,"
                  "moving,truth_share,verdict");
  int hits = 0;
  while (std::getline(lines, line)) {
    std::vector<std::string> f;
    std::istringstream fields(line);
    for (std::string v; std::getline(fields, v, ',');) f.push_back(v);
    ASSERT_EQ(f.size(), 19u) << line;
    const bool dynamic = std::stod(f[15]) > 0.5, mostly_true = std::stod(f[17]) >= 0.5;
    const std::string verdict = mostly_true ? (dynamic ? "hit" : "missed") : (dynamic ? "false" : "static");
    EXPECT_EQ(f[18], verdict) << line;
    EXPECT_NE(f[18], "static") << "left out without --all";
    hits += f[18] == "hit";
  }
  EXPECT_GT(hits, 0) << "the boxes' clusters found";
  const auto none = runFlowfusion("eval clusters " + (seq / "masks").string() + " " + (out / "masks").string());
  EXPECT_EQ(none.status, 2);
  EXPECT_NE(none.output.find("no cluster log"), std::string::npos) << none.output;
}

TEST(CmdEval, MapReportsTheFractionOfPointsBeyondTheThreshold) {
  ff::testing::TempDir dir;
  const std::string ref = writeGridPly(dir.path() / "ref.ply", 0);
  const std::string test = writeGridPly(dir.path() / "test.ply", 10);
  const auto r = runFlowfusion("eval map " + ref + " " + test + " --threshold 0.03");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NEAR(valueAfter(r.output, "test_to_reference.fraction_beyond_threshold"), 0.10, 1e-6);
  EXPECT_NEAR(valueAfter(r.output, "reference_to_test.fraction_beyond_threshold"), 0.0, 1e-6);
  const auto missing = runFlowfusion("eval map " + ref + " " + (dir.path() / "none.ply").string());
  EXPECT_EQ(missing.status, 2);
  EXPECT_NE(missing.output.find("none.ply"), std::string::npos) << missing.output;
}

// A sequence folder as REFERENCE: its depth at its ground-truth poses. Aligned by the ground truth
// itself (the identity), the figures are those without alignment; --align-by needs a sequence.
TEST(CmdEval, MapAgainstASequencesTruth) {
  ff::testing::TempDir dir;
  const std::string seq = (dir.path() / "seq").string();
  ASSERT_EQ(runFlowfusion("synth " + seq + " --frames 4 --width 96 --height 72 --people 0 --objects 0 --no-noise").status,
            0);
  const std::string test = writeGridPly(dir.path() / "test.ply", 10);
  const auto plain = runFlowfusion("eval map " + seq + " " + test + " --threshold 0.03");
  ASSERT_EQ(plain.status, 0) << plain.output;
  EXPECT_GT(valueAfter(plain.output, "reference_points"), 100);
  const auto aligned =
      runFlowfusion("eval map " + seq + " " + test + " --threshold 0.03 --align-by " + seq + "/groundtruth.txt");
  ASSERT_EQ(aligned.status, 0) << aligned.output;
  for (const char* key : {"test_to_reference.mean", "reference_to_test.fraction_beyond_threshold"})
    EXPECT_NEAR(valueAfter(aligned.output, key), valueAfter(plain.output, key), 1e-6) << key;
  const auto not_a_sequence =
      runFlowfusion("eval map " + test + " " + test + " --align-by " + seq + "/groundtruth.txt");
  EXPECT_EQ(not_a_sequence.status, 2);
  EXPECT_NE(not_a_sequence.output.find("--align-by"), std::string::npos) << not_a_sequence.output;
}

}  // namespace
}  // namespace ff::eval
