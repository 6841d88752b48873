#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "testing/test_util.h"

namespace ff::app {
namespace {

namespace fs = std::filesystem;
using ff::testing::runFlowfusion;

// The table's cells of the rows whose method is `method`, by sequence and column name.
std::map<std::string, std::map<std::string, std::string>> tableRows(const std::string& output,
                                                                    const std::string& method) {
  std::istringstream lines(output);
  std::string line;
  std::vector<std::string> headers;
  std::map<std::string, std::map<std::string, std::string>> rows;
  while (std::getline(lines, line)) {
    std::istringstream words(line);
    std::vector<std::string> cells;
    for (std::string w; words >> w;) cells.push_back(w);
    if (!cells.empty() && cells[0] == "sequence") headers = cells;
    if (headers.empty() || cells.size() != headers.size() || cells[1] != method) continue;
    for (size_t k = 0; k < cells.size(); ++k) rows[cells[0]][headers[k]] = cells[k];
  }
  return rows;
}

double numberAfter(const std::string& text, const std::string& key) {
  const auto pos = text.find(key);
  return pos == std::string::npos ? NAN : std::stod(text.substr(pos + key.size()));
}

// Two sequences with true masks and one without: each row gets its marked share (eval static's on
// the row's own masks), and the lines below the table the means of the rows with and without.
TEST(CmdBench, MarksPerSequenceAndTheMasksMeansOverTheSet) {
  ff::testing::TempDir dir;
  const std::string synth = " --frames 12 --width 96 --height 72 --objects 1 --people 0";
  for (const char* name : {"a", "b", "c"}) {
    const std::string seed = name == std::string("a") ? "2" : "5";
    ASSERT_EQ(runFlowfusion("synth " + (dir.path() / name).string() + synth + " --seed " + seed).status, 0);
  }
  fs::remove_all(dir.path() / "c" / "masks");
  const fs::path out = dir.path() / "out";
  const auto r = runFlowfusion("bench " + (dir.path() / "a").string() + " " + (dir.path() / "b").string() + " " +
                               (dir.path() / "c").string() + " --no-reference --out " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  auto rows = tableRows(r.output, "flowfusion");
  ASSERT_EQ(rows.size(), 3u) << r.output;
  EXPECT_EQ(rows["c"]["mIoU"], "-");
  for (const char* name : {"a", "b", "c"}) {
    const auto marks = runFlowfusion("eval static --json " + (out / name / "flowfusion" / "masks").string());
    ASSERT_EQ(marks.status, 0) << marks.output;
    const auto j = nlohmann::json::parse(marks.output);
    EXPECT_NEAR(std::stod(rows[name]["marked_%"]), 100 * j["mean_marked"].get<double>(), 0.006) << name;
    EXPECT_EQ(rows[name]["frames>5%"], std::to_string(j["frames_above"].get<size_t>())) << name;
  }
  const double mean_iou = (std::stod(rows["a"]["mIoU"]) + std::stod(rows["b"]["mIoU"])) / 2;
  EXPECT_NEAR(numberAfter(r.output, "mean of the 2 sequences with true masks: mIoU "), mean_iou, 0.0011) << r.output;
  EXPECT_EQ(r.output.find("sequences without"), std::string::npos) << "one sequence is no set: " << r.output;
}

}  // namespace
}  // namespace ff::app
