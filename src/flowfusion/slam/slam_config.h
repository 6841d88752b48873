#pragma once
// The `slam` section: loop closure over keyframes (slam/loop_closer.h). Keyframes are kept as the
// camera moves, a place index of randomized ferns proposes old keyframes that look like a new one,
// the dense odometry checks each proposal geometrically, and a pose graph over the keyframes
// (odometry and loop edges, each through a robust loss) is solved with Ceres on a background
// thread. docs/tuning.md#loop_closure holds the measurements behind the defaults.
#include <nlohmann/json.hpp>

#include "flowfusion/core/config_enum.h"

namespace ff {

enum class LoopClosureMode {
  Off,    // odometry only: drift is never corrected
  Ferns,  // randomized ferns propose, the dense odometry verifies, a Ceres pose graph corrects
};
FLOWFUSION_CONFIG_ENUM(LoopClosureMode, "slam.loop_closure", {LoopClosureMode::Off, "off"},
                       {LoopClosureMode::Ferns, "ferns"})

struct SlamConfig {
  // Without Ceres (libceres-dev) at build time, ferns is taken as off and a run says so.
  LoopClosureMode loop_closure = LoopClosureMode::Ferns;
  // A new keyframe once the camera moved this far from the last one (metres, degrees).
  double keyframe_translation_m = 0.2;
  double keyframe_rotation_deg = 15.0;
  // A keyframe whose verified loop lands within the keyframe thresholds above of an older keyframe
  // (its view already covered) keeps only its pose-graph node: its images leave, and it enters
  // neither the place index nor later checks, so memory follows the space covered, not the laps.
  bool cull_covered_keyframes = true;
  // Pyramid level of the input a keyframe keeps (1: 320x240 for VGA, about 300 kB a keyframe).
  int keyframe_level = 1;
  // Place index: ferns, each one pixel of an 80x60 image tested against four random thresholds
  // (blue, green, red, depth), compared only where both images are static and have depth.
  int fern_count = 500;
  int fern_image_width = 80;  // px; the height follows the camera's aspect ratio
  // A keyframe is a candidate when at least this share of the ferns valid in both agree.
  double min_similarity = 0.4;
  int candidates = 3;          // best candidates checked per new keyframe
  int min_keyframe_gap = 8;    // a candidate is at least this many keyframes older
  // Geometric check: the odometry of the new keyframe against the candidate converged, and this
  // share of its static pixels with depth land on the candidate within the inlier bounds.
  double min_inlier_fraction = 0.65;
  double inlier_depth_m = 0.02;  // * max(1, depth in metres)
  double inlier_intensity = 0.08;  // [0, 1] grey
  // And the same alignment run back (the candidate to the new keyframe, from the answer) lands
  // within one loop edge's standard deviations (loop_sigma_m, _deg) of it: people left unmasked
  // in either keyframe pull the two directions apart (docs/tuning.md#backward-check).
  bool backward_check = true;
  // The loop found may not move the new keyframe from where the graph has it by more than this.
  double max_correction_m = 0.5;
  double max_correction_deg = 20.0;
  // A solved graph moves the tracker and the map only when it moves some keyframe by more than
  // this: below, its own noise (a millimetre or two per loop edge) is no better than the tracker's
  // alignment to the map. The loop edges stay in the graph for the next solve, and the run's end
  // applies the last one whatever it moves.
  double min_correction_m = 0.01;
  double min_correction_deg = 0.5;
  // Pose graph: standard deviations of an odometry edge (between consecutive keyframes) and of a
  // loop edge, and the scales (in standard deviations) of the Cauchy losses they go through. The
  // odometry's too: where the tracking jumps (people it took for the scene moved it 7-20 cm between
  // two keyframes on the 320x240 loop), a quadratic edge keeps the jump and bends every lap around
  // it instead (docs/tuning.md#robust-odometry-edges); 0: quadratic.
  double odometry_sigma_m = 0.01;
  double odometry_sigma_deg = 0.5;
  double odometry_loss_scale = 2.0;
  double loop_sigma_m = 0.01;
  double loop_sigma_deg = 0.5;
  double loop_loss_scale = 2.0;
  // A keyframe's loop check runs on a background thread; its result is applied this many frames
  // later (the tracking thread waits there only if the check is still running), which keeps runs
  // reproducible whatever the thread timing.
  int apply_after_frames = 10;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(SlamConfig, loop_closure, keyframe_translation_m,
                                                keyframe_rotation_deg, cull_covered_keyframes, keyframe_level, fern_count, fern_image_width,
                                                min_similarity, candidates, min_keyframe_gap, min_inlier_fraction,
                                                inlier_depth_m, inlier_intensity, backward_check, max_correction_m,
                                                max_correction_deg, min_correction_m, min_correction_deg, odometry_sigma_m, odometry_sigma_deg,
                                                odometry_loss_scale, loop_sigma_m, loop_sigma_deg, loop_loss_scale, apply_after_frames)

// Throws InputError naming the setting when a value is out of range. `odometry_levels` bounds
// keyframe_level.
void validate(const SlamConfig& config, int odometry_levels);

// Whether this build can close loops (it found Ceres).
bool loopClosureAvailable();

}  // namespace ff
