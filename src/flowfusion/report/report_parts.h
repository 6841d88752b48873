#pragma once
// The sections of a report, each gathered from the run's files into the JSON the page's script
// draws from (report_page.cpp). Internal to the report stage; separate for testing and reading.
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "flowfusion/io/trajectory_io.h"

namespace ff::report {

// Standard base64 (RFC 4648, with padding), for images and binary arrays inside the page.
std::string base64(std::string_view bytes);

// The estimate against the ground truth: positions aligned onto the ground truth (Horn, as ATE),
// per-pose translation (m) and rotation (deg) error, ATE and RPE into `headline`. Without ground
// truth, the estimate alone. T_gt_est (alignment) is returned for the 3D view's ground-truth path.
struct TrajectorySection {
  nlohmann::json json;
  SE3 T_gt_est = SE3::Identity();
  bool aligned = false;
};
TrajectorySection trajectorySection(const Trajectory& est, const std::optional<Trajectory>& gt,
                                    double rpe_delta_s, nlohmann::json& headline);

// timings.csv ("timestamp,<stage>,..." per frame, empty = did not run): time since the first frame
// and each stage's ms per frame (null where it did not run). InputError naming the file when malformed.
nlohmann::json timingSection(const std::string& csv_path);

// A frame of the filmstrip: its mask, and where to find its colour image and ground-truth mask.
struct FilmFrame {
  double timestamp = 0;
  std::string mask_path;
  std::string color_path;    // "" without a sequence
  std::string gt_mask_path;  // "" without ground-truth masks
};
// Filmstrip entries (thumbnail, enlarged overlay, ground-truth overlay as JPEG data URLs, the dynamic
// area and the IoU when ground truth exists) for `even` frames spaced over the run and the
// `largest` frames of largest dynamic area among the others.
nlohmann::json filmstripSection(const std::vector<FilmFrame>& frames, int even, int largest, int thumb_width_px,
                                int large_width_px);

// The map (map_points.ply) subsampled to max_points and quantised to 16 bits per axis, the camera
// path, the ground-truth path in the map's frame (when given) and keyframe poses for frusta.
nlohmann::json mapSection(const std::string& ply_path, size_t max_points, const Trajectory& est,
                          const std::vector<Eigen::Vector3d>& gt_path_in_map);

// The HTML page: styles, three.js, the data and the script that draws it.
std::string renderPage(const nlohmann::json& data);

}  // namespace ff::report
