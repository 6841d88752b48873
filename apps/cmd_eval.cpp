// `flowfusion eval ate|rpe|seg|static|clusters|map`: the TUM benchmark's trajectory metrics, mask
// metrics, a run's cluster log against the true masks and the distance between two map point clouds.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <vector>

#include "command.h"
#include "flowfusion/core/atomic_file.h"
#include "flowfusion/core/error.h"
#include "flowfusion/eval/cluster_truth.h"
#include "flowfusion/eval/segmentation_metrics.h"
#include "flowfusion/eval/trajectory_metrics.h"
#include "flowfusion/fusion/map_compare.h"
#include "flowfusion/io/frame_source.h"
#include "flowfusion/io/trajectory_io.h"
#include "flowfusion/report/worst_masks.h"

namespace ff::app {
namespace {

struct EvalOptions {
  std::string gt, est;
  bool json = false;
  std::string sheet, sequence;  // eval seg: the contact sheet's path, the masks' sequence folder
  report::WorstMasksOptions sheet_options;
  bool overwrite = false;
  double max_diff_s = 0.02;
  double offset_s = 0;    // eval ate, rpe: added to EST's timestamps
  bool no_align = false;  // eval ate: compare the poses as they stand
  double delta_s = 1.0;
  double threshold_m = 0.03;
  double above = 0.05;  // eval static: a frame counts as falsely marked above this share
  int every = 2;           // eval map from a sequence: every this many frames
  int pixel_step = 2;      // eval map from a sequence: every this many pixels of a row and column
  double voxel_m = 0.004;  // eval map from a sequence: one truth point per cube of this size
  std::string align_by;    // eval map: the run's trajectory whose Horn alignment moves TEST
  std::string frames;      // eval clusters: FIRST:LAST of the true masks
  bool all = false;        // eval clusters: the static clusters too
};

void printStats(const char* prefix, const eval::ErrorStats& s, const char* unit) {
  const std::pair<const char*, double> rows[] = {{"rmse", s.rmse}, {"mean", s.mean}, {"median", s.median},
                                                 {"std", s.std},   {"min", s.min},   {"max", s.max}};
  for (const auto& [name, v] : rows) std::printf("%s.%s %f %s\n", prefix, name, v, unit);
}

void addOffsetOption(CLI::App* command, double& offset_s) {
  command
      ->add_option("--offset", offset_s,
                   "seconds added to EST's timestamps before the association, as the TUM scripts' --offset (a "
                   "camera stamped late, on arrival, against the ground truth's clock)")
      ->capture_default_str();
}

void runAte(const EvalOptions& o) {
  const Trajectory est = eval::withTimeOffset(readTrajectory(o.est), o.offset_s);
  const auto r = eval::computeAte(readTrajectory(o.gt), est, o.max_diff_s, o.gt, o.est,
                                  o.no_align ? eval::AteAlignment::None : eval::AteAlignment::Horn);
  if (o.json) {
    std::cout << nlohmann::json(r).dump(2) << '\n';
    return;
  }
  // The line names of evaluate_ate.py --verbose, so existing parsers keep working.
  std::printf("compared_pose_pairs %zu pairs\n", r.matched_poses);
  printStats("absolute_translational_error", r.translation_m, "m");
}

void runRpe(const EvalOptions& o) {
  const Trajectory est = eval::withTimeOffset(readTrajectory(o.est), o.offset_s);
  const auto r = eval::computeRpe(readTrajectory(o.gt), est, o.delta_s, o.gt, o.est);
  if (o.json) {
    std::cout << nlohmann::json(r).dump(2) << '\n';
    return;
  }
  // evaluate_rpe.py --verbose lines (errors over delta), then the rates per second.
  std::printf("compared_pose_pairs %zu pairs\n", r.pairs);
  printStats("translational_error", r.translation_m, "m");
  printStats("rotational_error", r.rotation_deg, "deg");
  std::printf("delta %f s\n", r.delta_s);
  std::printf("translational_error.rmse_per_second %f m/s\n", r.translation_rmse_m_per_s);
  std::printf("rotational_error.rmse_per_second %f deg/s\n", r.rotation_rmse_deg_per_s);
}

// The sheet's path is checked before any work: a PNG, not among the masks (it would be read as one
// next time), not replacing a file unless asked to.
void checkSheetPath(const EvalOptions& o) {
  namespace fs = std::filesystem;
  const fs::path sheet = fs::absolute(o.sheet).lexically_normal();
  if (sheet.extension() != ".png") throw InputError(o.sheet + ": the contact sheet is written as PNG (name it .png)");
  for (const std::string& masks : {o.gt, o.est})
    if (fs::exists(masks) && fs::exists(sheet.parent_path()) && fs::equivalent(sheet.parent_path(), masks))
      throw InputError(o.sheet + ": the contact sheet would lie among the masks of " + masks);
  if (fs::exists(sheet) && !o.overwrite) throw InputError(o.sheet + ": exists (give --overwrite to replace it)");
}

void writeSheet(const EvalOptions& o, const eval::SegmentationResult& r) {
  // In the TUM layout the ground-truth masks are the sequence's masks/ folder.
  const std::string sequence =
      o.sequence.empty() ? std::filesystem::absolute(o.gt).lexically_normal().parent_path().string() : o.sequence;
  writePngAtomic(o.sheet, report::worstMaskSheet(sequence, r, o.sheet_options), "contact sheet");
}

void runSeg(const EvalOptions& o) {
  if (!o.sheet.empty()) checkSheetPath(o);
  const auto r = eval::evaluateSegmentation(o.gt, o.est);
  if (!o.sheet.empty()) writeSheet(o, r);
  if (o.json) {
    std::cout << nlohmann::json(r).dump(2) << '\n';
    return;
  }
  std::printf("frames %zu (unmatched: %zu ground truth, %zu estimated)\n", r.frames, r.gt_unmatched,
              r.est_unmatched);
  std::printf("mean_iou %f\nmean_precision %f\nmean_recall %f\n", r.mean_iou, r.mean_precision, r.mean_recall);
  std::printf("pooled_iou %f\npooled_precision %f\npooled_recall %f\n", r.pooled.iou, r.pooled.precision,
              r.pooled.recall);
  const eval::IouLoss& l = r.iou_loss;
  std::printf("iou_lost_to.false_marks_without_mover %f\niou_lost_to.small_mover_missed %f\n"
              "iou_lost_to.mover_missed %f\niou_lost_to.false_marks_over_misses %f\n"
              "iou_lost_to.mover_partly_found %f\n",
              l.false_marks_without_mover, l.small_mover_missed, l.mover_missed, l.false_marks_over_misses,
              l.mover_partly_found);
}

void runStatic(const EvalOptions& o) {
  const auto r = eval::evaluateStaticMasks(o.est, o.above);
  if (o.json) {
    std::cout << nlohmann::json(r).dump(2) << '\n';
    return;
  }
  std::vector<const eval::StaticMaskFrame*> worst;
  for (const auto& f : r.per_frame) worst.push_back(&f);
  const size_t shown = std::min<size_t>(5, worst.size());
  std::partial_sort(worst.begin(), worst.begin() + shown, worst.end(),
                    [](const auto* a, const auto* b) { return a->marked > b->marked; });
  std::printf("frames %zu\nmean_marked %f\nmax_marked %f\nframes_above %zu (%.1f %% of the frames have more than "
              "%.1f %% marked)\n",
              r.frames, r.mean_marked, r.max_marked, r.frames_above, 100 * r.fraction_above, 100 * r.above);
  for (size_t k = 0; k < shown; ++k) std::printf("worst %s %f\n", worst[k]->path.c_str(), worst[k]->marked);
}

void printDifference(const char* prefix, const MapDifference& d) {
  std::printf("%s.mean %f m\n%s.median %f m\n%s.fraction_beyond_threshold %f\n", prefix, d.mean_m, prefix, d.median_m,
              prefix, d.fraction_beyond);
}

// A sequence's depth at its ground-truth poses (fusion/map_compare.h, TruthCloud).
std::vector<Eigen::Vector3f> sequenceTruthCloud(const EvalOptions& o, Trajectory& groundtruth) {
  const auto source = openFrameSource(o.gt, SequenceOptions{});
  const Trajectory* gt = source->groundtruth();
  if (!gt || gt->empty()) throw InputError("eval map: sequence '" + o.gt + "' has no groundtruth.txt");
  groundtruth = *gt;
  TruthCloud cloud(o.voxel_m);
  int index = 0, used = 0;
  while (auto frame = source->next()) {
    SE3 T_world_cam;
    if (index++ % o.every != 0 || !interpolatePose(*gt, frame->depthTime(), T_world_cam)) continue;
    cloud.addDepth(frame->depth, source->camera(), T_world_cam, o.pixel_step);
    ++used;
  }
  if (cloud.points().empty()) throw InputError("eval map: sequence '" + o.gt + "' gave no depth at a ground-truth pose");
  std::fprintf(stderr, "truth cloud: %zu points from %d frames of %s\n", cloud.points().size(), used, o.gt.c_str());
  return cloud.points();
}

void runMap(const EvalOptions& o) {
  const bool sequence = std::filesystem::is_directory(o.gt);
  Trajectory groundtruth;
  const auto reference = sequence ? sequenceTruthCloud(o, groundtruth) : readMapPoints(o.gt);
  auto test = readMapPoints(o.est);
  if (!o.align_by.empty()) {
    if (!sequence) throw InputError("eval map --align-by: REFERENCE must be a sequence folder with groundtruth.txt");
    const SE3 T_gt_est =
        eval::computeAte(groundtruth, readTrajectory(o.align_by), o.max_diff_s, o.gt, o.align_by).T_gt_est;
    for (Eigen::Vector3f& p : test) p = (T_gt_est * p.cast<double>()).cast<float>();
  }
  const auto r = compareMaps(reference, test, o.threshold_m);
  if (o.json) {
    std::cout << nlohmann::json(r).dump(2) << '\n';
    return;
  }
  std::printf("reference_points %zu points\ntest_points %zu points\nthreshold %f m\n", r.reference_to_test.points,
              r.test_to_reference.points, r.threshold_m);
  printDifference("test_to_reference", r.test_to_reference);
  printDifference("reference_to_test", r.reference_to_test);
}

void runClusters(const EvalOptions& o) {
  const FrameRange range = o.frames.empty() ? FrameRange{} : parseFrameRange(o.frames);
  const int last = range.last < 0 ? std::numeric_limits<int>::max() : range.last;
  std::cout << eval::clusterTruthCsv(eval::clusterTruth(o.gt, o.est), range.first, last, o.all);
}

const RegisterCommand kRegister{"50-eval", [](CLI::App& app) {
  auto* eval = app.add_subcommand("eval", "Evaluate trajectories (TUM ATE/RPE), dynamic masks and maps");
  eval->require_subcommand(1);
  auto opts = std::make_shared<EvalOptions>();

  auto* ate = eval->add_subcommand(
      "ate", "Absolute trajectory error after Horn alignment, as the TUM benchmark's evaluate_ate.py");
  ate->add_option("GT", opts->gt, "ground-truth trajectory (TUM format)")->required();
  ate->add_option("EST", opts->est, "estimated trajectory (TUM format)")->required();
  ate->add_option("--max-diff", opts->max_diff_s, "maximum timestamp difference for association, s")
      ->capture_default_str();
  addOffsetOption(ate, opts->offset_s);
  ate->add_flag("--json", opts->json, "print the result as JSON");
  ate->add_flag("--no-align", opts->no_align,
                "compare the poses as they stand, without the alignment (a run in the ground truth's frame, e.g. "
                "`run --map-in` in a map whose run started at the ground truth's first pose)");
  ate->callback([opts] { runAte(*opts); });

  auto* rpe = eval->add_subcommand(
      "rpe", "Relative pose error over a fixed time delta, as evaluate_rpe.py --fixed_delta --delta_unit s");
  rpe->add_option("GT", opts->gt, "ground-truth trajectory (TUM format)")->required();
  rpe->add_option("EST", opts->est, "estimated trajectory (TUM format)")->required();
  rpe->add_option("--delta", opts->delta_s, "time between the poses of a pair, s")->capture_default_str();
  addOffsetOption(rpe, opts->offset_s);
  rpe->add_flag("--json", opts->json, "print the result as JSON");
  rpe->callback([opts] { runRpe(*opts); });

  auto* seg = eval->add_subcommand(
      "seg", "IoU, precision and recall of dynamic masks (<timestamp>.png, >127 = dynamic)");
  seg->add_option("GT_MASKS", opts->gt, "folder of ground-truth masks")->required();
  seg->add_option("EST_MASKS", opts->est, "folder of estimated masks")->required();
  seg->add_flag("--json", opts->json, "print the result as JSON (with each frame's scores)");
  seg->add_option("--sheet", opts->sheet,
                  "also write a contact sheet (PNG) of the worst frames: colour, depth, true mask, estimate, both "
                  "compared");
  seg->add_option("--sheet-by", opts->sheet_options.by,
                  "worst = most pixels wrong (wrong-pixels) or lowest IoU (iou); default wrong-pixels")
      ->transform(CLI::CheckedTransformer(std::map<std::string, report::WorstBy>{
                                              {"wrong-pixels", report::WorstBy::kWrongPixels},
                                              {"iou", report::WorstBy::kIou}},
                                          CLI::ignore_case));
  seg->add_option("--sheet-rows", opts->sheet_options.rows, "frames on the contact sheet")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  seg->add_option("--sequence", opts->sequence,
                  "TUM folder of the masks' colour and depth images (default: the folder holding GT_MASKS)");
  seg->add_flag("--overwrite", opts->overwrite, "replace an existing contact sheet");
  seg->callback([opts] { runSeg(*opts); });

  auto* clusters = eval->add_subcommand(
      "clusters", "A run's cluster log (run --cluster-log) against the true masks: each cluster's evidence, "
                  "score, share of true pixels and verdict (hit, missed, false, static), as CSV");
  clusters->add_option("GT_MASKS", opts->gt, "folder of ground-truth masks")->required();
  clusters->add_option("CLUSTERS", opts->est, "the run's clusters/ folder")->required();
  clusters->add_option("--frames", opts->frames, "FIRST:LAST: only these frames (indices of the true masks)");
  clusters->add_flag("--all", opts->all, "also the clusters that are static in both (by default left out)");
  clusters->callback([opts] { runClusters(*opts); });

  auto* stat = eval->add_subcommand(
      "static", "False marks of a run on a static scene (every marked pixel is wrong): the share of each "
                "frame marked dynamic, no ground-truth masks needed");
  stat->add_option("EST_MASKS", opts->est, "folder of estimated masks (a run's masks/)")->required();
  stat->add_option("--above", opts->above, "count the frames with more than this share marked")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 0.999));
  stat->add_flag("--json", opts->json, "print the result as JSON (with each frame's share)");
  stat->callback([opts] { runStatic(*opts); });

  auto* map = eval->add_subcommand(
      "map", "Nearest-neighbour distances between two map point clouds (map_points.ply), both directions");
  map->add_option("REFERENCE", opts->gt,
                  "reference point cloud (PLY), or a sequence folder with ground truth: its depth at the "
                  "ground-truth poses (the room's truth for a synthetic static twin, synth --people 0 --no-noise)")
      ->required();
  map->add_option("TEST", opts->est, "point cloud compared with the reference (PLY)")->required();
  map->add_option("--threshold", opts->threshold_m, "distance beyond which a point counts as different, m")
      ->capture_default_str();
  map->add_option("--every", opts->every, "REFERENCE a sequence: every this many frames")
      ->capture_default_str()->check(CLI::PositiveNumber);
  map->add_option("--pixel-step", opts->pixel_step, "REFERENCE a sequence: every this many pixels")
      ->capture_default_str()->check(CLI::PositiveNumber);
  map->add_option("--voxel", opts->voxel_m, "REFERENCE a sequence: one point per cube of this size, m")
      ->capture_default_str()->check(CLI::PositiveNumber);
  map->add_option("--align-by", opts->align_by,
                  "REFERENCE a sequence: move TEST by the Horn alignment of this trajectory (the run's "
                  "trajectory.txt) onto the ground truth, as eval ate aligns, so only the map's own "
                  "inconsistency counts (doubled walls), not where its world frame landed");
  map->add_flag("--json", opts->json, "print the result as JSON");
  map->callback([opts] { runMap(*opts); });
}};

}  // namespace
}  // namespace ff::app
