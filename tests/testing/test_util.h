#pragma once
// Helpers shared by the test suites.
#include <gtest/gtest.h>

#include <filesystem>
#include <optional>
#include <string>

namespace ff::testing {

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
std::string sharedDataMissing();

// Runs the flowfusion executable with `args`; returns its exit status and combined output.
struct CommandResult {
  int status = -1;
  std::string output;
};
CommandResult runFlowfusion(const std::string& args);

}  // namespace ff::testing

#define FF_REQUIRE_SHARED_DATA(var)                                         \
  const auto var##_opt = ::ff::testing::sharedFr1Xyz();                      \
  if (!var##_opt) GTEST_SKIP() << ::ff::testing::sharedDataMissing();       \
  const std::string var = *var##_opt
