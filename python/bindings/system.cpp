// ff.System (the per-frame system, frames from NumPy arrays) and ff.Result.
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <opencv2/imgproc.hpp>

#include "bindings.h"
#include "convert.h"
#include "flowfusion/core/output_folder.h"
#include "flowfusion/core/undistortion.h"
#include "flowfusion/sinks/files_sink.h"
#include "flowfusion/pipeline/run.h"
#include "flowfusion/sinks/tracked_trajectory_sink.h"
#include "sequence.h"

namespace ff::py_bind {

namespace {

// Where a frame's mask goes back to the pixels of the image given: null when they are the same.
using RawPixels = std::shared_ptr<const Undistorter>;

cv::Mat inRawPixels(const RawPixels& raw, const cv::Mat& image) { return raw ? raw->toRawPixels(image) : image; }

// The system and what save() needs of the frames it processed (their masks, in the pixels the
// system worked in, with the mapping back to the pixels of the image given).
class PySystem {
 public:
  PySystem(const CameraModel& camera, const SystemConfig& config, const SE3& T_world_first, bool keep_masks,
           const SavedMap* map_in)
      : system_(config, camera.intrinsics, T_world_first, map_in), keep_masks_(keep_masks) {
    if (map_in) map_in_ = map_in->path;
    if (!camera.distortion.none()) undistorter_ = std::make_shared<Undistorter>(camera.intrinsics, camera.distortion);
  }

  // Called without the GIL. `raw` takes the frame's pixels back to those of the image given; the
  // result's mask is returned in those. `sequence_dir`: the folder the frame came from, or "".
  FrameResult process(const RgbdFrame& frame, const RawPixels& raw, const std::string& sequence_dir) {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (!std::isfinite(frame.timestamp)) throw BadArgument("timestamp: must be finite");
    if (frames_ > 0 && !(frame.timestamp > last_timestamp_))
      throw BadArgument("timestamp: " + std::to_string(frame.timestamp) + " is not after the previous frame's " +
                        std::to_string(last_timestamp_) + " (frames must come in time order)");
    FrameResult r = system_.process(frame);
    last_timestamp_ = frame.timestamp;
    ++frames_;
    rounds_ += r.iterations;
    if (!sequence_dir.empty() && std::find(inputs_.begin(), inputs_.end(), sequence_dir) == inputs_.end())
      inputs_.push_back(sequence_dir);
    if (keep_masks_) masks_.push_back({frame.timestamp, r.dynamic_mask.clone(), raw});
    r.dynamic_mask = inRawPixels(raw, r.dynamic_mask);
    return r;
  }

  // FilesSink driven as runSequence drives it, so the files are those `flowfusion run` writes. The
  // output may not be, contain or lie inside a sequence the frames came from (the check `run` makes).
  std::vector<std::string> save(const std::string& out_dir, bool overwrite, const PySequence* sequence,
                                bool export_map) {
    const std::lock_guard<std::mutex> lock(mutex_);
    std::vector<std::string> inputs = inputs_;
    if (sequence) inputs.push_back(sequence->sequence().dir());
    for (const auto& input : inputs) refuseOverlap(out_dir, input, "the input sequence");
    if (!map_in_.empty()) refuseOverlap(out_dir, map_in_, "the map_in map");
    FilesSinkOptions options;
    options.out_dir = out_dir;
    options.overwrite = overwrite;
    options.write_masks = keep_masks_;
    options.export_map = export_map;
    FilesSink sink(options);
    const std::string name =
        sequence ? std::filesystem::absolute(sequence->sequence().dir()).lexically_normal().string() : "python";
    setOutputCommand("run");
    const OutputRelease release;
    TrackedTrajectorySink tracked(out_dir);
    sink.begin({name, nullptr, system_.config(), system_.camera(), frames_});
    // A frame without its own mapping takes the sequence's (arrays cut from its frames).
    for (const auto& kept : masks_)
      sink.writeMask(kept.timestamp, kept.raw || !sequence ? inRawPixels(kept.raw, kept.mask)
                                                           : sequence->source().toRawPixels(kept.mask));
    system_.finishLoopClosure();  // the loop checks still running, as at the end of a run
    RunSummary s;
    s.frames = frames_;
    summariseSystem(s, system_, rounds_);
    sink.end(s, system_.map());
    tracked.end(s, system_.map());
    return s.written;
  }

  const FlowFusionSystem& system() const { return system_; }
  const RawPixels& undistorter() const { return undistorter_; }
  size_t frames() const { return frames_; }

 private:
  struct KeptMask {
    double timestamp;
    cv::Mat mask;  // the system's pixels
    RawPixels raw;
  };

  std::mutex mutex_;
  FlowFusionSystem system_;
  RawPixels undistorter_;  // the camera's lens distortion: arrays are raw images
  bool keep_masks_;
  std::vector<KeptMask> masks_;
  std::vector<std::string> inputs_;  // sequence folders of the frames processed
  std::string map_in_;               // the saved map's file it continues in, or empty
  size_t frames_ = 0;
  long rounds_ = 0;
  double last_timestamp_ = 0;
};

// depth_timestamp: None (the colour image's time) or a finite number of seconds.
double depthTime(const py::object& t) {
  if (t.is_none()) return std::numeric_limits<double>::quiet_NaN();
  const bool number = !py::isinstance<py::bool_>(t) && !py::isinstance<py::str>(t) && py::hasattr(t, "__float__");
  if (!number)
    throw py::type_error("depth_timestamp: expected None or a number of seconds, got " +
                         py::str(py::type::of(t).attr("__name__")).cast<std::string>());
  const double seconds = py::float_(t).cast<double>();
  if (!std::isfinite(seconds)) throw BadArgument("depth_timestamp: must be finite, got " + std::to_string(seconds));
  return seconds;
}

// The frame from user arrays: RGB or grey uint8, depth uint16 (depth_scale per metre) or float32
// metres, undistorted when the system's camera has lens distortion. Every argument is checked
// before any pixel is read; the conversions run without the GIL.
FrameResult processArrays(PySystem& s, const py::array& rgb, const py::array& depth, double timestamp,
                          const py::object& depth_timestamp, double depth_scale) {
  const CameraIntrinsics& camera = s.system().camera();
  const cv::Size size(camera.width, camera.height);
  const bool grey = rgb.ndim() == 2;
  const MatView colour = viewOfArray(rgb, "rgb", CV_8U, grey ? 1 : 3, size);
  const bool raw = py::isinstance<py::array_t<uint16_t>>(depth);
  if (!raw && !py::isinstance<py::array_t<float>>(depth))
    throw BadArgument("depth: expected dtype uint16 (raw, depth_scale units per metre) or float32 (metres), got " +
                      py::str(depth.dtype()).cast<std::string>());
  const MatView d = viewOfArray(depth, "depth", raw ? CV_16U : CV_32F, 1, size);
  checkDepthScale(depth_scale, "depth_scale");
  RgbdFrame frame;
  frame.timestamp = timestamp;
  frame.depth_timestamp = depthTime(depth_timestamp);
  // The views are read without the GIL (as NumPy's own functions do); they outlive `release`.
  py::gil_scoped_release release;
  cv::cvtColor(colour.mat, frame.color, grey ? cv::COLOR_GRAY2BGR : cv::COLOR_RGB2BGR);
  if (raw) {
    d.mat.convertTo(frame.depth, CV_32F, 1.0 / depth_scale);
  } else {
    frame.depth = d.mat.clone();
    cv::patchNaNs(frame.depth, 0.0);
    if (!cv::checkRange(frame.depth, true, nullptr, 0.0, 1e4))
      throw BadArgument("depth: float32 depth must be finite metres in [0, 10000] (0 or NaN = no measurement)");
  }
  if (const RawPixels& u = s.undistorter()) {
    frame.color = u->undistortColor(frame.color);
    frame.depth = u->undistortDepth(frame.depth);  // nearest: the same for raw units and metres
  }
  frame.intensity = intensityFromBgr(frame.color);
  return s.process(frame, s.undistorter(), "");
}

py::tuple mapPoints(const PySystem& s) {
  MapPoints p;
  if (const StaticMap* map = s.system().map()) p = map->points();
  const auto n = static_cast<py::ssize_t>(p.positions.size());
  py::array_t<float> positions({n, py::ssize_t{3}}), normals({n, py::ssize_t{3}});
  py::array_t<uint8_t> colours({n, py::ssize_t{3}});
  auto P = positions.mutable_unchecked<2>();
  auto N = normals.mutable_unchecked<2>();
  auto C = colours.mutable_unchecked<2>();
  for (py::ssize_t i = 0; i < n; ++i)
    for (int j = 0; j < 3; ++j) {
      P(i, j) = p.positions[i][j];
      N(i, j) = p.normals[i][j];
      C(i, j) = p.colors[i][2 - j];  // BGR -> RGB
    }
  return py::make_tuple(positions, colours, normals);
}

py::dict timings(const PySystem& s) {
  const Timings& t = s.system().timings();
  py::dict median;
  for (const auto& stage : t.stages()) median[py::str(stage)] = t.medianMs(stage);
  py::dict out;
  out["median_ms"] = median;
  out["frame_total_ms"] = py::cast(t.frameTotals());
  return out;
}

// Result.clusters: the cluster log as columns (numpy arrays) and the label image.
py::object clusterColumns(const ClusterLog& log) {
  if (log.empty()) return py::none();
  const size_t n = log.clusters.size();
  py::array_t<int32_t> pixels(n);
  py::array_t<bool> moving(n);
  const std::pair<const char*, double ClusterRecord::*> reals[] = {
      {"u_px", &ClusterRecord::u_px},   {"v_px", &ClusterRecord::v_px},     {"depth_m", &ClusterRecord::depth_m},
      {"r_I", &ClusterRecord::r_I},     {"r_D_m", &ClusterRecord::r_D_m},   {"r_F_px", &ClusterRecord::r_F_px},
      {"r_M_m", &ClusterRecord::r_M_m}, {"a_M", &ClusterRecord::a_M},       {"prior", &ClusterRecord::prior},
      {"memory", &ClusterRecord::memory}, {"delta", &ClusterRecord::delta}, {"b", &ClusterRecord::b}};
  py::dict out;
  out["labels"] = arrayFromMat(log.labels);
  for (size_t c = 0; c < n; ++c) {
    pixels.mutable_at(c) = log.clusters[c].pixels;
    moving.mutable_at(c) = log.clusters[c].moving;
  }
  out["pixels"] = pixels;
  for (const auto& [name, member] : reals) {
    py::array_t<double> column(n);
    for (size_t c = 0; c < n; ++c) column.mutable_at(c) = log.clusters[c].*member;
    out[name] = column;
  }
  out["moving"] = moving;
  return out;
}

// ff.Result: what System.process returns.
void bindResult(py::module_& m) {
  py::class_<FrameResult>(m, "Result", "What System.process returns for one frame.")
      .def_readonly("timestamp", &FrameResult::timestamp, "Seconds.")
      .def_property_readonly("T_world_cam", [](const FrameResult& r) { return arrayFromPose(r.T_world_cam); },
                             "4x4 float64 camera-to-world pose.")
      .def_property_readonly("dynamic_mask", [](const FrameResult& r) { return arrayFromMat(r.dynamic_mask); },
                             "HxW uint8, 255 = dynamic, in the pixels of the image passed in, as `flowfusion run` "
                             "writes masks: for process(frame) those of the frame's image file (the raw, distorted "
                             "image when the sequence undistorts, e.g. TUM fr1, fr2); for process(rgb, depth, ...) "
                             "those of the arrays (raw when the System's camera has lens distortion and undistorts "
                             "them itself).")
      .def_property_readonly(
          "scores",
          [](const FrameResult& r) -> py::object {
            if (r.scores.empty()) return py::none();
            return arrayFromMat(r.scores);
          },
          "Dynamic score b per pixel at the segmentation level (float32), or None without segmentation.")
      .def_property_readonly("clusters", [](const FrameResult& r) { return clusterColumns(r.clusters); },
                             "With the setting pipeline.cluster_log: a dict of each cluster's evidence and score "
                             "(numpy arrays indexed by cluster: pixels, u_px, v_px, depth_m, r_I, r_D_m, r_F_px, "
                             "r_M_m, a_M, prior, memory, delta, b, moving; docs/formats.md) and 'labels', the "
                             "cluster of each pixel at the segmentation level (int32, -1 = none); else None.")
      .def_readonly("tracking_ok", &FrameResult::tracking_ok, "False when the tracker lost the camera.")
      .def_readonly("has_pose", &FrameResult::has_pose,
                    "False before a System continuing in a saved map (map_in) is localized in it.")
      .def_readonly("message", &FrameResult::message, "What the tracker did when it did not simply succeed.")
      .def_readonly("used_model", &FrameResult::used_model, "Aligned to the map's prediction.")
      .def_readonly("restarted_from_flow", &FrameResult::restarted_from_flow,
                    "The odometry restarted from the flow's rigid consensus.")
      .def_readonly("iterations", &FrameResult::iterations, "Segmentation rounds.");
}

}  // namespace

void bindSystem(py::module_& m) {
  bindResult(m);
  py::class_<PySystem>(m, "System",
                       "The FlowFusion system: feed frames in time order with process(); it tracks the camera, "
                       "segments moving objects and maps the static scene.")
      .def(py::init([](const CameraModel& camera, const std::optional<SystemConfig>& config,
                       const py::object& T_world_first, bool keep_masks,
                       const std::optional<std::filesystem::path>& map_in) {
             const SE3 T = T_world_first.is_none() ? SE3::Identity() : poseFromArray(T_world_first, "T_world_first");
             const SystemConfig c = config.value_or(SystemConfig{});
             std::optional<SavedMap> map;
             if (map_in) map = readMapFor(map_in->string(), "", camera.intrinsics, c.slam);
             return std::make_unique<PySystem>(camera, c, T, keep_masks, map ? &*map : nullptr);
           }),
           py::arg("camera"), py::arg("config") = py::none(), py::arg("T_world_first") = py::none(),
           py::arg("keep_masks") = true, py::arg("map_in") = py::none(),
           "System(camera, config=None, T_world_first=None, keep_masks=True): camera an ff.Camera; with lens "
           "distortion (ff.Camera.preset('fr1')) process(rgb, depth, ...) takes raw images and undistorts them as "
           "`flowfusion run` does, with seq.camera (pinhole) it takes the frames of a TumSequence as they are. "
           "config an ff.Config (defaults when None), T_world_first the 4x4 pose of the first frame (identity when "
           "None; seq.initial_pose() starts as `flowfusion run`). keep_masks keeps each frame's mask for save() "
           "(W*H bytes a frame). map_in: a previous run's folder (or its map.ffmap) to continue in, as `flowfusion run "
           "--map-in`: T_world_first is then unused, each frame is sought in the map until one is found (Result."
           "tracking_ok False before). ValueError naming the first bad setting, or the map file and why it does not "
           "fit.")
      .def(
          "process",
          [](PySystem& s, const PyFrame& f) {
            const CameraIntrinsics& c = s.system().camera();
            if (f.frame.width() != c.width || f.frame.height() != c.height)
              throw BadArgument("frame: the image is " + std::to_string(f.frame.width()) + "x" +
                                std::to_string(f.frame.height()) + " (WxH), the camera is " + std::to_string(c.width) +
                                "x" + std::to_string(c.height));
            py::gil_scoped_release release;
            return s.process(f.frame, f.raw, f.sequence_dir);
          },
          py::arg("frame"),
          "process(frame) -> Result for an ff.Frame of a TumSequence: the frame as `flowfusion run` feeds it "
          "(its depth image's own timestamp included), so a loop of process(frame) gives the run's trajectory "
          "and masks. The form to use with a TumSequence.")
      .def("process", &processArrays, py::arg("rgb"), py::arg("depth"), py::arg("timestamp"),
           py::arg("depth_timestamp") = py::none(), py::arg("depth_scale") = 5000.0,
           "process(rgb, depth, timestamp, depth_timestamp=None, depth_scale=5000.0) -> Result, for frames from "
           "your own source. rgb: HxWx3 uint8 RGB or HxW uint8 grey; depth: HxW uint16 (depth_scale units per "
           "metre, 100 to 65535) or float32 metres (0 or NaN = no measurement); both of the camera's size; "
           "timestamp in seconds, increasing; depth_timestamp the depth image's time (None: the same as "
           "timestamp). To reproduce `flowfusion run` on a TumSequence pass depth_timestamp=frame.depth_timestamp "
           "(or use process(frame)): without it the depth is taken at the colour image's time and the trajectory "
           "differs where the two differ (TUM: up to 20 ms). ValueError or TypeError naming the argument before "
           "any pixel is read; releases the GIL while it runs.")
      .def(
          "trajectory", [](const PySystem& s) { return arrayFromTrajectory(s.system().trajectory()); },
          "The poses so far, Nx8 float64: t tx ty tz qx qy qz qw (TUM, camera-to-world).")
      .def("map_points", &mapPoints,
           "The static map's stable surfels: (positions Nx3 float32 metres, colours Nx3 uint8 RGB, normals Nx3 "
           "float32); empty with fusion off.")
      .def("timings", &timings, "{'median_ms': {stage: ms}, 'frame_total_ms': [ms per frame]}.")
      .def(
          "save",
          [](PySystem& s, const std::filesystem::path& out_dir, bool overwrite, const PySequence* sequence,
             bool export_map) {
            py::gil_scoped_release release;
            return s.save(out_dir.string(), overwrite, sequence, export_map);
          },
          py::arg("out_dir"), py::arg("overwrite") = false, py::arg("sequence") = nullptr,
          py::arg("export_map") = true,
          "save(out_dir, overwrite=False, sequence=None, export_map=True) -> list of written paths: the files "
          "`flowfusion run` writes (config.json, trajectory.txt, masks/, timings.csv, map.ply, map_points.ply, "
          "preview/, summary.json), masks in the pixels Result.dynamic_mask gives. With the TumSequence the "
          "frames came from, arrays cut from its frames have their masks taken back to its raw pixels and "
          "summary.json names it, as a run's. ValueError when out_dir is not empty and overwrite is False, when "
          "another process writes into it, or when it is, contains or lies inside the sequence (or one the "
          "processed frames came from): results never go into an input.")
      .def_property_readonly("frames", &PySystem::frames, "Frames processed so far.")
      .def_property_readonly("config", [](const PySystem& s) { return s.system().config(); }, "The ff.Config in use.")
      .def_property_readonly("camera", [](const PySystem& s) { return CameraModel{s.system().camera(), {}}; },
                             "The pinhole camera in use.");
}

}  // namespace ff::py_bind
