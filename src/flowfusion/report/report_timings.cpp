// The timing section: timings.csv as per-stage series over the run.
#include <cmath>
#include <fstream>
#include <sstream>

#include "flowfusion/core/error.h"
#include "flowfusion/report/report_parts.h"

namespace ff::report {
namespace {

std::vector<std::string> splitCsv(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) cells.push_back(cell);
  if (!line.empty() && line.back() == ',') cells.emplace_back();  // a trailing empty cell
  return cells;
}

double parseNumber(const std::string& cell, const std::string& path, size_t line_no) {
  try {
    size_t used = 0;
    const double v = std::stod(cell, &used);
    if (used == cell.size()) return v;
  } catch (const std::exception&) {
  }
  throw InputError(path + ":" + std::to_string(line_no) + ": not a number: '" + quoteForMessage(cell) + "'");
}

}  // namespace

nlohmann::json timingSection(const std::string& csv_path) {
  std::ifstream in(csv_path);
  if (!in) throw InputError(csv_path + ": cannot be read");
  std::string line;
  if (!std::getline(in, line)) throw InputError(csv_path + ": empty (expected a header 'timestamp,<stage>,...')");
  const std::vector<std::string> header = splitCsv(line);
  if (header.empty() || header[0] != "timestamp")
    throw InputError(csv_path + ":1: the header must start with 'timestamp'");
  const size_t stages = header.size() - 1;
  std::vector<nlohmann::json> series(stages, nlohmann::json::array());
  nlohmann::json t = nlohmann::json::array();
  double t0 = NAN;
  for (size_t line_no = 2; std::getline(in, line); ++line_no) {
    if (line.empty()) continue;
    const auto cells = splitCsv(line);
    if (cells.size() != header.size())
      throw InputError(csv_path + ":" + std::to_string(line_no) + ": " + std::to_string(cells.size()) +
                       " cells, the header has " + std::to_string(header.size()));
    const double stamp = cells[0].empty() ? NAN : parseNumber(cells[0], csv_path, line_no);
    if (std::isnan(t0)) t0 = stamp;
    t.push_back(std::isnan(stamp) ? nlohmann::json() : nlohmann::json(std::round((stamp - t0) * 1e4) / 1e4));
    for (size_t s = 0; s < stages; ++s) {
      const std::string& c = cells[s + 1];
      series[s].push_back(c.empty() ? nlohmann::json()
                                    : nlohmann::json(std::round(parseNumber(c, csv_path, line_no) * 100) / 100));
    }
  }
  nlohmann::json j;
  j["t"] = t;
  j["stages"] = nlohmann::json::array();
  for (size_t s = 0; s < stages; ++s) j["stages"].push_back({{"name", header[s + 1]}, {"ms", series[s]}});
  return j;
}

}  // namespace ff::report
