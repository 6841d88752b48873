#pragma once
// A plain-text table shared by `flowfusion bench` and `flowfusion eval` (statistics and stage
// timings are in core/timings.h, the peak memory in core/process_memory.h).
#include <string>
#include <vector>

#include "flowfusion/core/timings.h"

namespace ff::eval {

// Fixed-width text table: one header row, a rule, then the rows. Cells that read as numbers are
// right-aligned, other cells left-aligned, headers of all-numeric columns right-aligned; columns
// are as wide as their widest cell.
class TextTable {
 public:
  explicit TextTable(std::vector<std::string> headers);
  // Rows shorter than the header are padded with empty cells; longer ones are an error
  // (std::invalid_argument: a programming mistake, not bad input).
  void addRow(std::vector<std::string> cells);
  std::string str() const;
  // Fixed-point formatting for numeric cells; NaN prints as "-".
  static std::string num(double value, int decimals = 3);

 private:
  std::vector<std::string> headers_;
  std::vector<std::vector<std::string>> rows_;
};

}  // namespace ff::eval
