#include "flowfusion/io/tum_text.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <tuple>

#include "flowfusion/core/error.h"

namespace ff {

RecordReader::RecordReader(std::string path, const std::string& what, std::string format)
    : path_(std::move(path)), format_(std::move(format)) {
  std::error_code ec;
  if (std::filesystem::is_directory(path_, ec)) throw InputError(path_ + ": is a folder, not a " + what);
  in_.open(path_);
  if (!in_) throw InputError(path_ + ": cannot open " + what);
}

bool RecordReader::next() {
  while (std::getline(in_, line_)) {
    ++lineno_;
    const auto first = line_.find_first_not_of(" \t\r");
    if (first == std::string::npos || line_[first] == '#') continue;
    fields_ = std::istringstream(line_);
    return true;
  }
  read_all_ = true;
  return false;
}

double RecordReader::timestamp() {
  double t;
  if (!(fields_ >> t) || !std::isfinite(t)) malformed();
  if (std::abs(t) >= kMaxTimestampS) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", t);
    fail("timestamp " + std::string(buf) + " s is out of range (expected seconds below 1e10, e.g. Unix time)");
  }
  if (previous_ && t <= *previous_)
    fail("timestamp " + std::to_string(t) +
         (t == *previous_ ? " is a duplicate" : " is earlier than the previous line") +
         " (timestamps must be strictly increasing)");
  previous_ = t;
  return t;
}

void RecordReader::malformed() const { fail("expected '" + format_ + "', got '" + quoteForMessage(line_) + "'"); }

void RecordReader::fail(const std::string& message) const {
  throw InputError(read_all_ ? path_ + ": " + message : path_ + ":" + std::to_string(lineno_) + ": " + message);
}

std::vector<std::pair<size_t, size_t>> associate(const std::vector<double>& a, const std::vector<double>& b,
                                                 double max_diff, StampLimit limit) {
  // Sorted inputs: the candidates of a_i lie in a window of b. Sorting the candidates by
  // (difference, a, b) is associate.py's sort of (diff, stamp_a, stamp_b) tuples.
  const bool inclusive = limit == StampLimit::kInclusive;
  std::vector<std::tuple<double, size_t, size_t>> cand;
  size_t lo = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    const double from = a[i] - max_diff, to = a[i] + max_diff;
    while (lo < b.size() && (inclusive ? b[lo] < from : b[lo] <= from)) ++lo;
    for (size_t j = lo; j < b.size() && (inclusive ? b[j] <= to : b[j] < to); ++j) {
      const double d = std::abs(a[i] - b[j]);
      // The scripts compare the difference itself, which rounding can put on or past the limit
      // for a stamp inside the window.
      if (inclusive || d < max_diff) cand.emplace_back(d, i, j);
    }
  }
  std::sort(cand.begin(), cand.end());
  std::vector<char> used_a(a.size(), 0), used_b(b.size(), 0);
  std::vector<std::pair<size_t, size_t>> out;
  for (const auto& [d, i, j] : cand) {
    if (used_a[i] || used_b[j]) continue;
    used_a[i] = used_b[j] = 1;
    out.emplace_back(i, j);
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace ff
