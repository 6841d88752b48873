// The `flowfusion` executable on bad input: exit status 2 and a message naming the culprit,
// with nothing overwritten. Needs the flowfusion_app target built.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "testing/test_util.h"

namespace fs = std::filesystem;

namespace ff {
namespace {

// A valid two-frame 64x48 sequence with camera.txt.
std::string makeSequence(const fs::path& root) {
  fs::create_directories(root / "rgb");
  fs::create_directories(root / "depth");
  std::ofstream rgb(root / "rgb.txt"), depth(root / "depth.txt");
  for (const char* t : {"1.000000", "1.033333"}) {
    cv::imwrite((root / "rgb" / (std::string(t) + ".png")).string(), cv::Mat(48, 64, CV_8UC3, cv::Scalar(40, 90, 160)));
    cv::imwrite((root / "depth" / (std::string(t) + ".png")).string(), cv::Mat(48, 64, CV_16U, cv::Scalar(6000)));
    rgb << t << " rgb/" << t << ".png\n";
    depth << t << " depth/" << t << ".png\n";
  }
  std::ofstream(root / "camera.txt") << "50 50 31.5 23.5 64 48\n";
  return root.string();
}

std::string shellArg(const fs::path& p) { return "'" + p.string() + "'"; }

TEST(CliErrors, RunOnMissingFolder) {
  testing::TempDir tmp;
  const fs::path missing = tmp.path() / "no_such_sequence";
  const auto r = testing::runFlowfusion("run " + shellArg(missing) + " --out " + shellArg(tmp.path() / "out"));
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find(missing.string()), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(tmp.path() / "out"));
}

TEST(CliErrors, RunIntoNonEmptyOutWithoutOverwrite) {
  testing::TempDir tmp;
  const std::string seq = makeSequence(tmp.path() / "seq");
  const fs::path out = tmp.path() / "out";
  fs::create_directories(out);
  std::ofstream(out / "trajectory.txt") << "precious\n";
  const auto r = testing::runFlowfusion("run " + shellArg(seq) + " --out " + shellArg(out) + " --quiet");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find(out.string()), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("--overwrite"), std::string::npos) << r.output;
  std::ifstream in(out / "trajectory.txt");
  std::string content;
  std::getline(in, content);
  EXPECT_EQ(content, "precious");
  EXPECT_EQ(std::distance(fs::directory_iterator(out), fs::directory_iterator{}), 1);
}

TEST(CliErrors, BadSettingValue) {
  testing::TempDir tmp;
  const std::string seq = makeSequence(tmp.path() / "seq");
  const auto r = testing::runFlowfusion("run " + shellArg(seq) + " --out " + shellArg(tmp.path() / "out") +
                                        " --set odometry.levels=0");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("odometry.levels"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(tmp.path() / "out"));
}

TEST(CliErrors, UnknownSetting) {
  testing::TempDir tmp;
  const std::string seq = makeSequence(tmp.path() / "seq");
  const auto r = testing::runFlowfusion("run " + shellArg(seq) + " --out " + shellArg(tmp.path() / "out") +
                                        " --set nosuch.key=1");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("nosuch"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(tmp.path() / "out"));
}

TEST(CliErrors, NoIntrinsics) {
  testing::TempDir tmp;
  const std::string seq = makeSequence(tmp.path() / "plain");
  fs::remove(fs::path(seq) / "camera.txt");
  const auto r = testing::runFlowfusion("run " + shellArg(seq) + " --out " + shellArg(tmp.path() / "out"));
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("--camera"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace ff
