#pragma once
// Helpers shared by the test suites.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>

#include "flowfusion/core/se3.h"

namespace ff::testing {

inline constexpr double kDeg = M_PI / 180.0;

// exp([t_m; axis_angle_rad]): a translation in metres and a rotation vector in radians.
inline SE3 motion(const Eigen::Vector3d& t_m, const Eigen::Vector3d& axis_angle_rad) {
  Vector6d xi;
  xi << t_m, axis_angle_rad;
  return expSE3(xi);
}

// A fresh, empty temporary folder removed when the object goes out of scope.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::string str() const { return path_.string(); }

 private:
  std::filesystem::path path_;
};

// The shared fr1/xyz frames (../shared/data/tum/fr1_xyz_head300 or $FLOWFUSION_SHARED_DATA),
// or nullopt when absent; tests then GTEST_SKIP() with the message from sharedDataMissing().
std::optional<std::string> sharedFr1Xyz();
// Any of the shared TUM sequences by name (e.g. "fr1_rpy_head150"), or nullopt when absent.
std::optional<std::string> sharedTum(const std::string& name);
std::string sharedDataMissing();

// Exit status (128 + signal when killed) and combined output of a command.
struct CommandResult {
  int status = -1;
  std::string output;
};
// `script` run by sh, its standard output and error together.
CommandResult runShell(const std::string& script);
// The flowfusion executable with `args`, after `shell_prefix` (e.g. "ulimit -f 16") when given.
CommandResult runFlowfusion(const std::string& args, const std::string& shell_prefix = "");

// A valid two-frame 64x48 TUM-layout sequence with camera.txt under `root`; returns root.
std::filesystem::path makeTinySequence(const std::filesystem::path& root);

// The message of the InputError `f` throws, or "no InputError".
std::string inputErrorOf(const std::function<void()>& f);

}  // namespace ff::testing

#define FF_REQUIRE_SHARED_DATA(var)                                         \
  const auto var##_opt = ::ff::testing::sharedFr1Xyz();                      \
  if (!var##_opt) GTEST_SKIP() << ::ff::testing::sharedDataMissing();       \
  const std::string var = *var##_opt
