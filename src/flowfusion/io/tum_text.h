#pragma once
// What the TUM RGB-D benchmark's text files have in common: a record per line with '#' comment
// lines (file lists, trajectories, camera.txt), and timestamps that are paired across files.
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace ff {

// Timestamps are seconds below this in magnitude (Unix time until the year 2286): larger ones
// would lose their microseconds in "%.6f" file names and trajectories.
inline constexpr double kMaxTimestampS = 1e10;

// Reads records one line at a time, skipping blank and '#' lines. Every error is an InputError
// naming the file and the line at fault, so that a user can fix the file.
class RecordReader {
 public:
  // `what` names the kind of file ("file list") when it cannot be opened; `format` spells out a
  // record ("timestamp filename") for the message on a malformed line.
  RecordReader(std::string path, const std::string& what, std::string format);

  // Moves to the next record; false once the file is read.
  bool next();
  const std::string& line() const { return line_; }
  // The record's fields not read yet.
  std::istringstream& fields() { return fields_; }
  // Reads the record's leading timestamp: finite, below kMaxTimestampS in magnitude, and later
  // than the previous record's.
  double timestamp();

  // "path:line: expected '<format>', got '<line>'".
  [[noreturn]] void malformed() const;
  // "path:line: message", or "path: message" once the file is read (about the file as a whole).
  [[noreturn]] void fail(const std::string& message) const;

 private:
  std::string path_, format_;
  std::ifstream in_;
  std::string line_;
  std::istringstream fields_;
  int lineno_ = 0;
  bool read_all_ = false;
  std::optional<double> previous_;
};

// Whether a pair of timestamps exactly max_diff apart counts as associated.
enum class StampLimit {
  kInclusive,  // |dt| <= max_diff: colour-depth association of sequences
  kExclusive,  // |dt| <  max_diff: the benchmark's evaluation scripts
};

// Pairs sorted timestamp lists a and b greedily by smallest difference (ties: earlier a, then
// earlier b), each index used at most once, only differences within max_diff. Returns index
// pairs (i, j) sorted by i.
std::vector<std::pair<size_t, size_t>> associate(const std::vector<double>& a, const std::vector<double>& b,
                                                 double max_diff, StampLimit limit);

}  // namespace ff
