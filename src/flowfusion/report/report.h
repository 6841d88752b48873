#pragma once
// `flowfusion report`: one self-contained HTML page (RUN_DIR/report.html) showing what a run did:
// the headline figures, the trajectory against the ground truth coloured by its error, the error
// and the per-stage time over the run, a filmstrip of the dynamic masks and an interactive 3D view
// of the static map with the camera path. Everything (three.js, images, data) is inside the file,
// and its Content-Security-Policy forbids any request, so it opens offline in any browser.
#include <cstddef>
#include <string>
#include <vector>

namespace ff::report {

struct ReportOptions {
  std::string run_dir;   // what `flowfusion run` wrote (trajectory.txt, masks/, summary.json, ...)
  // TUM-layout folder of the run's frames: colour images for the overlays, groundtruth.txt and
  // masks/ for the errors. Empty: the run's summary.json names it (used when that folder exists).
  std::string sequence;
  size_t max_map_points = 60000;  // the 3D view shows at most this many of map_points.ply
  int even_frames = 8;            // filmstrip frames evenly spaced over the run
  int largest_frames = 4;         // filmstrip frames with the largest dynamic area
  int thumb_width_px = 200;       // filmstrip thumbnails
  int large_width_px = 640;       // the enlarged frame shown on a click (never upscaled)
  double rpe_delta_s = 1.0;       // RPE pair spacing; shortened to a quarter of a shorter run
};

// Reads the run's files, writes RUN_DIR/report.html (atomically) and returns its path. InputError
// naming the file when the run folder or its trajectory.txt is missing or a file is malformed;
// optional parts (ground truth, masks, timings, map) that are absent are said so in the page, and
// in `notes` when given (a missing sequence folder or ground truth, no shared timestamps).
std::string writeReport(const ReportOptions& options, std::vector<std::string>* notes = nullptr);

}  // namespace ff::report
