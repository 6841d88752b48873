#include "flowfusion/eval/bench_utils.h"

#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "flowfusion/core/error.h"

namespace ff::eval {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

bool looksNumeric(const std::string& s) {
  if (s == "-") return true;  // TextTable::num's NaN
  if (s.empty()) return false;
  char* end = nullptr;
  std::strtod(s.c_str(), &end);
  return end && *end == '\0';
}
}  // namespace

double median(std::vector<double> values) {
  if (values.empty()) return kNaN;
  const size_t n = values.size();
  const auto mid = values.begin() + static_cast<std::ptrdiff_t>(n / 2);
  std::nth_element(values.begin(), mid, values.end());
  const double upper = *mid;
  if (n % 2 == 1) return upper;
  const double lower = *std::max_element(values.begin(), mid);
  return 0.5 * (lower + upper);
}

double mean(const std::vector<double>& values) {
  if (values.empty()) return kNaN;
  double sum = 0;
  for (double v : values) sum += v;
  return sum / static_cast<double>(values.size());
}

double peakResidentMiB() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  // Linux reports ru_maxrss in KiB.
  return static_cast<double>(usage.ru_maxrss) / 1024.0;
}

TextTable::TextTable(std::vector<std::string> headers) : headers_(std::move(headers)) {}

void TextTable::addRow(std::vector<std::string> cells) {
  if (cells.size() > headers_.size())
    throw std::invalid_argument("TextTable::addRow: " + std::to_string(cells.size()) + " cells for " +
                                std::to_string(headers_.size()) + " columns");
  cells.resize(headers_.size());
  rows_.push_back(std::move(cells));
}

std::string TextTable::num(double value, int decimals) {
  if (std::isnan(value)) return "-";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, value);
  return buf;
}

std::string TextTable::str() const {
  std::vector<size_t> width(headers_.size());
  for (size_t c = 0; c < headers_.size(); ++c) {
    width[c] = headers_[c].size();
    for (const auto& r : rows_) width[c] = std::max(width[c], r[c].size());
  }
  // A header sits over its column's numbers: right-aligned when every cell below reads as one.
  std::vector<char> numeric_column(headers_.size(), !rows_.empty());
  for (const auto& r : rows_)
    for (size_t c = 0; c < r.size(); ++c)
      if (!r[c].empty() && !looksNumeric(r[c])) numeric_column[c] = 0;
  std::ostringstream out;
  const auto emit = [&](const std::vector<std::string>& cells, bool header) {
    std::string line;
    for (size_t c = 0; c < cells.size(); ++c) {
      if (c) line += "  ";
      const std::string pad(width[c] - cells[c].size(), ' ');
      const bool right = header ? numeric_column[c] : looksNumeric(cells[c]);
      line += right ? pad + cells[c] : cells[c] + pad;
    }
    line.erase(line.find_last_not_of(' ') + 1);
    out << line << '\n';
  };
  emit(headers_, true);
  size_t total = 0;
  for (size_t c = 0; c < width.size(); ++c) total += width[c] + (c ? 2 : 0);
  out << std::string(total, '-') << '\n';
  for (const auto& r : rows_) emit(r, false);
  return out.str();
}

void Timings::beginFrame(double timestamp_s) {
  rows_.push_back({timestamp_s, std::vector<double>(stages_.size(), kNaN)});
}

size_t Timings::stageIndex(const std::string& stage) {
  const auto it = std::find(stages_.begin(), stages_.end(), stage);
  if (it != stages_.end()) return static_cast<size_t>(it - stages_.begin());
  stages_.push_back(stage);
  for (auto& r : rows_) r.ms.push_back(kNaN);
  return stages_.size() - 1;
}

void Timings::add(const std::string& stage, double ms) {
  if (rows_.empty()) beginFrame(kNaN);
  const size_t i = stageIndex(stage);
  double& cell = rows_.back().ms[i];
  cell = std::isnan(cell) ? ms : cell + ms;
}

std::vector<double> Timings::samples(const std::string& stage) const {
  std::vector<double> out;
  const auto it = std::find(stages_.begin(), stages_.end(), stage);
  if (it == stages_.end()) return out;
  const size_t i = static_cast<size_t>(it - stages_.begin());
  for (const auto& r : rows_)
    if (!std::isnan(r.ms[i])) out.push_back(r.ms[i]);
  return out;
}

double Timings::medianMs(const std::string& stage) const { return median(samples(stage)); }
double Timings::meanMs(const std::string& stage) const { return mean(samples(stage)); }

std::vector<double> Timings::frameTotals() const {
  std::vector<double> totals;
  for (const Row& r : rows_) {
    double sum = 0;
    for (double ms : r.ms)
      if (!std::isnan(ms)) sum += ms;
    totals.push_back(sum);
  }
  return totals;
}

nlohmann::json Timings::toJson() const {
  nlohmann::json j;
  j["stages"] = nlohmann::json::object();
  for (const auto& s : stages_) {
    const auto v = samples(s);
    j["stages"][s] = {{"median_ms", median(v)}, {"mean_ms", mean(v)}, {"frames", v.size()}};
  }
  j["frames"] = nlohmann::json::array();
  for (const auto& r : rows_) {
    nlohmann::json f;
    f["timestamp"] = std::isnan(r.timestamp_s) ? nlohmann::json(nullptr) : nlohmann::json(r.timestamp_s);
    for (size_t i = 0; i < stages_.size(); ++i)
      if (!std::isnan(r.ms[i])) f[stages_[i]] = r.ms[i];
    j["frames"].push_back(std::move(f));
  }
  return j;
}

std::string Timings::toCsv() const {
  std::ostringstream out;
  out << "timestamp";
  for (const auto& s : stages_) out << ',' << s;
  out << '\n';
  char buf[64];
  for (const auto& r : rows_) {
    if (!std::isnan(r.timestamp_s)) {
      std::snprintf(buf, sizeof buf, "%.6f", r.timestamp_s);
      out << buf;
    }
    for (double ms : r.ms) {
      out << ',';
      if (!std::isnan(ms)) {
        std::snprintf(buf, sizeof buf, "%.4f", ms);
        out << buf;
      }
    }
    out << '\n';
  }
  return out.str();
}

void Timings::writeCsv(const std::string& path) const {
  std::ofstream out(path);
  if (!out) throw InputError(path + ": cannot write timings file");
  out << toCsv();
  if (!out) throw InputError(path + ": error while writing timings file");
}

StageTimer::StageTimer(Timings& timings, std::string stage)
    : timings_(timings), stage_(std::move(stage)), start_(std::chrono::steady_clock::now()) {}

StageTimer::~StageTimer() { stop(); }

double StageTimer::stop() {
  if (stopped_) return 0;
  stopped_ = true;
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start_).count();
  timings_.add(stage_, ms);
  return ms;
}

}  // namespace ff::eval
