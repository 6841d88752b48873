#pragma once
// Dynamic-object segmentation metrics: estimated masks against ground-truth masks.
// Masks are 8-bit images, dynamic where the value is above 127 (written as 255), static elsewhere.
#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <string>
#include <utility>
#include <vector>

namespace ff::eval {

// Pixel counts of the dynamic class and the scores derived from them. Convention for empty
// classes: a ratio 0/0 counts as 1 (nothing to get wrong): precision is 1 when nothing is
// predicted dynamic, recall is 1 when nothing is dynamic in the ground truth, and IoU is 1 when
// neither mask has a dynamic pixel. A frame predicting nothing where the ground truth has dynamic
// pixels thus scores precision 1, recall 0, IoU 0.
struct MaskScores {
  int64_t true_positive = 0, false_positive = 0, false_negative = 0;
  double iou = 1, precision = 1, recall = 1;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(MaskScores, true_positive, false_positive, false_negative, iou, precision,
                                   recall)

// A mask file read as 8-bit grey (colour masks are converted). InputError naming the file when it
// cannot be read or is not 8-bit.
cv::Mat readMaskFile(const std::string& path);

// Scores from counts, with the 0/0 convention above.
MaskScores scoresFromCounts(int64_t true_positive, int64_t false_positive, int64_t false_negative);

// Both masks CV_8UC1 of the same size; throws InputError otherwise (gt_name/est_name name them).
MaskScores compareMasks(const cv::Mat& gt, const cv::Mat& est, const std::string& gt_name = "ground-truth mask",
                        const std::string& est_name = "estimated mask");

// One matched pair of masks and its scores.
struct FrameMaskScores {
  std::string gt_path, est_path;
  double timestamp = 0;  // the ground-truth mask's timestamp (its name), s; NaN when the name is not a number
  MaskScores scores;
  int64_t pixels = 0;  // the masks' size, width x height
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(FrameMaskScores, gt_path, est_path, timestamp, scores, pixels)

// Where the mean IoU goes: each frame's 1 - IoU over the frame count, under the one thing that
// frame shows, so that the five add up to 1 - mean IoU. A mover is missed when under a fifth of
// it is found and the frame's IoU is under 0.2; it is small under small_mover_share of the image.
// docs/tuning.md uses it to say what the augmented real scenes lose.
struct IouLoss {
  double false_marks_without_mover = 0;  // nothing dynamic in the truth, something marked
  double small_mover_missed = 0;
  double mover_missed = 0;
  double false_marks_over_misses = 0;  // a mover found, more false pixels than missed ones
  double mover_partly_found = 0;       // a mover found, at least as many missed pixels as false ones
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(IouLoss, false_marks_without_mover, small_mover_missed, mover_missed,
                                   false_marks_over_misses, mover_partly_found)

// 0.0065 of the image: 2,000 pixels at 640x480.
IouLoss iouLoss(const std::vector<FrameMaskScores>& frames, double small_mover_share = 0.0065);

struct SegmentationResult {
  size_t frames = 0;           // matched mask pairs
  size_t gt_unmatched = 0;     // ground-truth masks without an estimated mask
  size_t est_unmatched = 0;    // estimated masks without a ground-truth mask
  double mean_iou = 0, mean_precision = 0, mean_recall = 0;  // over frames
  MaskScores pooled;           // counts and scores over all pixels of all frames together
  IouLoss iou_loss;            // iouLoss(per_frame)
  std::vector<FrameMaskScores> per_frame;  // the pairs, timestamped ones first, in time order
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(SegmentationResult, frames, gt_unmatched, est_unmatched, mean_iou,
                                   mean_precision, mean_recall, pooled, iou_loss, per_frame)

// Masks (and a run's per-frame files) are matched by the timestamps in their names within this, s.
constexpr double kMaxMaskStampDiffS = 0.02;

// The regular files `dir`/<timestamp><extension> by time; with `named`, the others with that
// extension too (stem -> path). The folder must exist.
std::vector<std::pair<double, std::string>> stampedFiles(const std::string& dir, const std::string& extension,
                                                         std::map<std::string, std::string>* named = nullptr);

// Folders of <timestamp>.png masks. Files are matched by the timestamp in their names (nearest
// within 0.02 s, each used once, as associate.py); names that are not numbers match by identical
// name. Masks are read as 8-bit grey (colour masks are converted). InputError naming the folder
// or file on a missing folder, no mask in it, no matching pair, an unreadable or non-8-bit file,
// or a size mismatch.
SegmentationResult evaluateSegmentation(const std::string& gt_dir, const std::string& est_dir);

// Masks of a run on a static scene, where every marked pixel is wrong (no ground-truth masks
// needed): the share of each frame marked dynamic.
struct StaticMaskFrame {
  std::string path;
  double timestamp = 0;   // from the name, s; NaN when the name is not a number
  double marked = 0;      // share of the frame's pixels marked dynamic, [0, 1]
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(StaticMaskFrame, path, timestamp, marked)

struct StaticMaskResult {
  size_t frames = 0;
  double mean_marked = 0;           // mean over frames of the marked share, [0, 1]
  double max_marked = 0;
  double above = 0.05;              // the share a frame must exceed to count in frames_above
  size_t frames_above = 0;          // frames with more than `above` marked
  double fraction_above = 0;        // frames_above / frames
  std::vector<StaticMaskFrame> per_frame;  // timestamped ones first, in time order
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(StaticMaskResult, frames, mean_marked, max_marked, above, frames_above,
                                   fraction_above, per_frame)

// Reads every <timestamp>.png of `est_dir` (as evaluateSegmentation does). `above` in [0, 1).
// InputError naming the folder or file on a missing folder, no mask, an unreadable file.
StaticMaskResult evaluateStaticMasks(const std::string& est_dir, double above = 0.05);

}  // namespace ff::eval
