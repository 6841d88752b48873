#pragma once
// Small helpers shared by `flowfusion bench`, `flowfusion eval` and the pipeline's timing output:
// summary statistics, peak memory, a plain-text table and per-frame per-stage timings.
#include <chrono>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace ff::eval {

// Median as numpy.median: the mean of the two middle values for an even count; NaN when empty.
double median(std::vector<double> values);
double mean(const std::vector<double>& values);  // NaN when empty

// Peak resident set size of this process so far (getrusage ru_maxrss), MiB.
double peakResidentMiB();

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

// Per-frame, per-stage wall times in milliseconds. A frame is opened with beginFrame(); add()
// accumulates into the open frame (a stage timed twice in one frame sums), so every row holds the
// frame's total time per stage. Stages keep the order in which they were first seen.
class Timings {
 public:
  void beginFrame(double timestamp_s);
  // Opens a frame with a NaN timestamp when none is open yet.
  void add(const std::string& stage, double ms);

  const std::vector<std::string>& stages() const { return stages_; }
  size_t frames() const { return rows_.size(); }
  // The stage's times over the frames in which it ran.
  std::vector<double> samples(const std::string& stage) const;
  double medianMs(const std::string& stage) const;
  double meanMs(const std::string& stage) const;
  // Each frame's time summed over its stages.
  std::vector<double> frameTotals() const;

  // {"stages": {name: {"median_ms", "mean_ms", "frames"}}, "frames": [{"timestamp", name: ms}]}.
  nlohmann::json toJson() const;
  // Header "timestamp,<stage>,..." then one line per frame; a stage that did not run is empty.
  std::string toCsv() const;
  // Throws InputError naming the path when it cannot be written.
  void writeCsv(const std::string& path) const;

 private:
  struct Row {
    double timestamp_s;
    std::vector<double> ms;  // by stage index; NaN = did not run
  };
  size_t stageIndex(const std::string& stage);
  std::vector<std::string> stages_;
  std::vector<Row> rows_;
};

// Scoped timer: adds the elapsed time to `timings` under `stage` when stopped or destroyed.
class StageTimer {
 public:
  StageTimer(Timings& timings, std::string stage);
  ~StageTimer();
  StageTimer(const StageTimer&) = delete;
  StageTimer& operator=(const StageTimer&) = delete;
  // Records now and returns the elapsed ms; later calls and the destructor record nothing.
  double stop();

 private:
  Timings& timings_;
  std::string stage_;
  std::chrono::steady_clock::time_point start_;
  bool stopped_ = false;
};

}  // namespace ff::eval
