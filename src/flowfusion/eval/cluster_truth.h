#pragma once
// A run's cluster log (`run --cluster-log`: clusters/<timestamp>.csv with .png beside it) against
// the true masks: each cluster's share of true dynamic pixels beside what the scores made of it,
// so that the evidence behind a missed mover or a false mark can be read row by row
// (`flowfusion eval clusters`, docs/formats.md).
#include <string>
#include <vector>

namespace ff::eval {

enum class ClusterVerdict { kHit, kMissed, kFalse, kStatic };
const char* verdictName(ClusterVerdict v);

struct ClusterTruthRow {
  int frame = 0;          // index of the matched true mask among the truth's, by time
  double timestamp = 0;   // the log's
  std::string record;     // the log's CSV row as written
  double truth_share = 0;  // of the cluster's pixels in the true mask; NaN when it has none in the labels
  double b = 0;            // its dynamic score
  // true share at least 0.5: hit (b > 0.5) or missed; else false (b > 0.5) or static. The written
  // mask may differ from b > 0.5 (pipeline.mask_* rules).
  ClusterVerdict verdict = ClusterVerdict::kStatic;
};

struct ClusterTruth {
  std::string header;  // the logs' CSV header
  std::vector<ClusterTruthRow> rows;
};

// Every log of `clusters_dir` whose timestamp has a true mask (<timestamp>.png within 0.02 s) in
// `gt_dir`. InputError naming the folder or file when a folder is missing or holds no log, a label
// image is missing or of another size than its mask, or a row does not parse.
ClusterTruth clusterTruth(const std::string& gt_dir, const std::string& clusters_dir);

// "frame,timestamp,<the log's columns>,truth_share,verdict" and the rows from frame `first` to `last`
// (inclusive), all of them or only those not static.
std::string clusterTruthCsv(const ClusterTruth& truth, int first, int last, bool all);

}  // namespace ff::eval
