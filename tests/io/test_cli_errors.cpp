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
  const std::string seq = testing::makeTinySequence(tmp.path() / "seq").string();
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
  const std::string seq = testing::makeTinySequence(tmp.path() / "seq").string();
  const auto r = testing::runFlowfusion("run " + shellArg(seq) + " --out " + shellArg(tmp.path() / "out") +
                                        " --set odometry.levels=0");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("odometry.levels"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(tmp.path() / "out"));
}

TEST(CliErrors, UnknownSetting) {
  testing::TempDir tmp;
  const std::string seq = testing::makeTinySequence(tmp.path() / "seq").string();
  const auto r = testing::runFlowfusion("run " + shellArg(seq) + " --out " + shellArg(tmp.path() / "out") +
                                        " --set nosuch.key=1");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("nosuch"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(tmp.path() / "out"));
}

TEST(CliErrors, NoIntrinsics) {
  testing::TempDir tmp;
  const std::string seq = testing::makeTinySequence(tmp.path() / "plain");
  fs::remove(fs::path(seq) / "camera.txt");
  const auto r = testing::runFlowfusion("run " + shellArg(seq) + " --out " + shellArg(tmp.path() / "out"));
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("--camera"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace ff
