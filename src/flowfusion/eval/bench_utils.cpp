#include "flowfusion/eval/bench_utils.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
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

}  // namespace ff::eval
