// Two commands writing into one output folder at once (issue 30, case 7), through the executable:
// the second is refused with a clear error and a non-zero exit while the first goes on, and the
// first's result is whole (its own config, trajectory and a manifest listing each file once).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include "flowfusion/core/config.h"
#include "flowfusion/core/output_folder.h"
#include "flowfusion/io/trajectory_io.h"
#include "testing/test_util.h"

namespace ff {
namespace {

namespace fs = std::filesystem;

TEST(OutputLock, ASecondRunIntoTheSameFolderIsRefusedWhileTheFirstWrites) {
  testing::TempDir tmp;
  const std::string seq = (tmp.path() / "seq").string(), out = (tmp.path() / "out").string();
  ASSERT_EQ(testing::runFlowfusion("synth " + seq + " --frames 80 --width 160 --height 120").status, 0);
  // The second run starts once the first has written a few masks, and asks for --overwrite; the
  // first is stopped (SIGSTOP) meanwhile, so on a loaded machine it cannot end before the second starts.
  const std::string app = FLOWFUSION_APP_PATH;
  const std::string script =
      app + " run " + seq + " --out " + out + " --quiet --no-map > " + tmp.str() + "/first.log 2>&1 & pid=$!; " +
      "for i in $(seq 1200); do n=$(ls " + out + "/masks 2>/dev/null | wc -l); [ \"$n\" -ge 3 ] && break; sleep 0.05; " +
      "done; kill -STOP $pid; " + app + " run " + seq + " --out " + out + " --overwrite --quiet --no-map " +
      "--set pipeline.max_iterations=2; second=$?; kill -CONT $pid; wait $pid; first=$?; echo \"first=$first second=$second\"";
  const auto r = testing::runShell(script);
  EXPECT_NE(r.output.find("first=0 second=2"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("another flowfusion command is writing into this output folder"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find(out), std::string::npos) << r.output;

  const nlohmann::json summary = readJsonFile(out + "/summary.json");
  EXPECT_TRUE(summary["complete"].get<bool>());
  EXPECT_EQ(summary["frames"].get<int>(), 80);
  EXPECT_EQ(readTrajectory(out + "/trajectory.txt").size(), 80u);
  EXPECT_NE(readJsonFile(out + "/config.json")["pipeline"]["max_iterations"].get<int>(), 2) << "the first's config";
  std::ifstream manifest(out + "/" + kManifestName);
  std::set<std::string> listed;
  for (std::string line; std::getline(manifest, line);)
    if (!line.empty() && line[0] != '#') EXPECT_TRUE(listed.insert(line).second) << "listed twice: " << line;
  EXPECT_EQ(listed.count("trajectory.txt"), 1u);

  // Once the first has ended the folder is free again.
  const auto again = testing::runFlowfusion("run " + seq + " --out " + out + " --overwrite --quiet --no-map");
  EXPECT_EQ(again.status, 0) << again.output;
}

}  // namespace
}  // namespace ff
