#include "flowfusion/core/timings.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "flowfusion/core/atomic_file.h"

namespace ff {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
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
  writeFileAtomic(path, toCsv(), "timings file");
}

double msSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

StageTimer::StageTimer(Timings& timings, std::string stage)
    : timings_(timings), stage_(std::move(stage)), start_(std::chrono::steady_clock::now()) {}

StageTimer::~StageTimer() { stop(); }

double StageTimer::stop() {
  if (stopped_) return 0;
  stopped_ = true;
  const double ms = msSince(start_);
  timings_.add(stage_, ms);
  return ms;
}

}  // namespace ff
