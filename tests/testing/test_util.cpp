#include "testing/test_util.h"

#include <array>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <sys/wait.h>

#include "flowfusion/core/error.h"

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

std::optional<std::string> sharedFr1Xyz() { return sharedTum("fr1_xyz_head300"); }

std::optional<std::string> sharedTum(const std::string& name) {
  const char* env = std::getenv("FLOWFUSION_SHARED_DATA");
  const std::filesystem::path base = env && *env ? env : "../shared/data";
  const auto p = base / "tum" / name;
  if (std::filesystem::exists(p / "rgb.txt")) return std::filesystem::canonical(p).string();
  return std::nullopt;
}

std::string sharedDataMissing() {
  return "shared TUM data not found (set FLOWFUSION_SHARED_DATA to the folder holding tum/fr1_xyz_head300); "
         "skipping this real-data test";
}

CommandResult runShell(const std::string& script) {
  CommandResult r;
  FILE* pipe = popen(("{ " + script + "; } 2>&1").c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf{};
  while (size_t n = std::fread(buf.data(), 1, buf.size(), pipe)) r.output.append(buf.data(), n);
  const int st = pclose(pipe);
  r.status = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
  return r;
}

CommandResult runFlowfusion(const std::string& args, const std::string& shell_prefix) {
  return runShell((shell_prefix.empty() ? "" : shell_prefix + "; ") + "exec " + FLOWFUSION_APP_PATH + " " + args);
}

std::filesystem::path makeTinySequence(const std::filesystem::path& root) {
  namespace fs = std::filesystem;
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
  return root;
}

std::string inputErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "no InputError";
}

}  // namespace ff::testing
