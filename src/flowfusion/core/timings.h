#pragma once
// Per-frame, per-stage wall times of the pipeline (what `run` writes as timings.csv and `bench`
// tabulates) and the summary statistics they are reported with.
#include <chrono>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace ff {

// Median as numpy.median: the mean of the two middle values for an even count; NaN when empty.
double median(std::vector<double> values);
double mean(const std::vector<double>& values);  // NaN when empty

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

// Wall time in milliseconds since `start` (steady clock).
double msSince(std::chrono::steady_clock::time_point start);

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

}  // namespace ff
