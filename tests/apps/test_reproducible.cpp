// Issue 16, case 10: the same input and configuration give byte-identical trajectories, masks and
// maps, run after run and whatever the number of threads (taskset limits the run to one CPU;
// TBB and OpenCV size their pools by the process's affinity).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "testing/test_util.h"

namespace fs = std::filesystem;

namespace ff {
namespace {

std::string q(const fs::path& p) { return "'" + p.string() + "'"; }

std::string readAll(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The files a run's result consists of (timings and the summary's timings differ by nature).
void expectSameResults(const fs::path& a, const fs::path& b) {
  size_t compared = 0;
  for (const auto& e : fs::recursive_directory_iterator(a)) {
    const std::string name = e.path().filename().string();
    if (!e.is_regular_file() || name == "timings.csv" || name == "summary.json" || name == ".flowfusion-manifest")
      continue;
    const fs::path other = b / fs::relative(e.path(), a);
    ASSERT_TRUE(fs::exists(other)) << other;
    EXPECT_TRUE(readAll(e.path()) == readAll(other)) << "differs: " << fs::relative(e.path(), a);
    ++compared;
  }
  EXPECT_GT(compared, 20u);  // trajectory, config, 20 masks, the map files
}

TEST(Reproducible, DynamicRunIsByteIdenticalAcrossRunsAndThreadCounts) {
  testing::TempDir tmp;
  const fs::path seq = tmp.path() / "seq";
  ASSERT_EQ(testing::runFlowfusion("synth " + q(seq) + " --width 160 --height 120 --frames 20 --seed 5 --objects 2")
                .status,
            0);
  const std::string run = "run " + q(seq) + " --quiet --out ";
  ASSERT_EQ(testing::runFlowfusion(run + q(tmp.path() / "a")).status, 0);
  ASSERT_EQ(testing::runFlowfusion(run + q(tmp.path() / "b")).status, 0);
  expectSameResults(tmp.path() / "a", tmp.path() / "b");
  if (std::system("taskset -c 0 true >/dev/null 2>&1") != 0) GTEST_SKIP() << "taskset is not available";
  const std::string one_cpu = "sh -c \"taskset -c 0 " + std::string(FLOWFUSION_APP_PATH) + " " + run +
                              q(tmp.path() / "c") + "\" >/dev/null 2>&1";
  ASSERT_EQ(std::system(one_cpu.c_str()), 0);
  expectSameResults(tmp.path() / "a", tmp.path() / "c");
}

}  // namespace
}  // namespace ff
