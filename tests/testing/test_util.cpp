#include "testing/test_util.h"

#include <array>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <sys/wait.h>

namespace ff::testing {

TempDir::TempDir() {
  std::random_device rd;
  path_ = std::filesystem::temp_directory_path() / ("flowfusion_test_" + std::to_string(rd()) + std::to_string(rd()));
  std::filesystem::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

std::optional<std::string> sharedFr1Xyz() {
  const char* env = std::getenv("FLOWFUSION_SHARED_DATA");
  const std::filesystem::path base = env && *env ? env : "../shared/data";
  const auto p = base / "tum" / "fr1_xyz_head300";
  if (std::filesystem::exists(p / "rgb.txt")) return std::filesystem::canonical(p).string();
  return std::nullopt;
}

std::string sharedDataMissing() {
  return "shared TUM data not found (set FLOWFUSION_SHARED_DATA to the folder holding tum/fr1_xyz_head300); "
         "skipping this real-data test";
}

CommandResult runFlowfusion(const std::string& args) {
  const std::string cmd = std::string(FLOWFUSION_APP_PATH) + " " + args + " 2>&1";
  CommandResult r;
  FILE* pipe = popen(cmd.c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf{};
  while (fgets(buf.data(), buf.size(), pipe)) r.output += buf.data();
  const int st = pclose(pipe);
  r.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  return r;
}

}  // namespace ff::testing
