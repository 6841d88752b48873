// ff.eval (the metrics of `flowfusion eval ... --json`), ff.synth (`flowfusion synth`) and ff.run
// (`flowfusion run`: the same loop and files, in-process).
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "bindings.h"
#include "convert.h"
#include "flowfusion/core/config.h"
#include "flowfusion/eval/segmentation_metrics.h"
#include "flowfusion/eval/trajectory_metrics.h"
#include "flowfusion/sinks/files_sink.h"
#include "flowfusion/pipeline/run.h"
#include "flowfusion/synth/synthetic_scene.h"

namespace ff::py_bind {

namespace {

std::string nameOf(const py::handle& object, const std::string& fallback) {
  return py::isinstance<py::str>(object) || py::hasattr(object, "__fspath__")
             ? object.cast<std::filesystem::path>().string()
             : fallback;
}

py::object ate(const py::object& gt, const py::object& est, double max_diff, double offset) {
  const Trajectory g = trajectoryFromObject(gt, "gt");
  const Trajectory e = eval::withTimeOffset(trajectoryFromObject(est, "est"), offset);
  return pythonFromJson(eval::computeAte(g, e, max_diff, nameOf(gt, "gt"), nameOf(est, "est")));
}

py::object rpe(const py::object& gt, const py::object& est, double delta, double offset) {
  const Trajectory g = trajectoryFromObject(gt, "gt");
  const Trajectory e = eval::withTimeOffset(trajectoryFromObject(est, "est"), offset);
  return pythonFromJson(eval::computeRpe(g, e, delta, nameOf(gt, "gt"), nameOf(est, "est")));
}

py::object seg(const std::filesystem::path& gt_dir, const std::filesystem::path& est_dir) {
  requireExists(gt_dir, "gt_masks_dir");
  requireExists(est_dir, "est_masks_dir");
  eval::SegmentationResult r;
  {
    py::gil_scoped_release release;
    r = eval::evaluateSegmentation(gt_dir.string(), est_dir.string());
  }
  return pythonFromJson(r);
}

std::string synthesise(const std::filesystem::path& out_dir, uint64_t seed, int frames, int objects, bool overwrite,
                       const py::kwargs& settings) {
  nlohmann::json j = synth::SynthConfig{};
  j["seed"] = seed;
  j["frames"] = frames;
  j["objects"] = objects;
  const auto text = py::module_::import("json").attr("dumps")(settings).cast<std::string>();
  mergeConfig(j, nlohmann::json::parse(text), "synth settings");
  const auto config = j.get<synth::SynthConfig>();
  checkConverted(j, nlohmann::json(config));
  py::gil_scoped_release release;
  setOutputCommand("synth");
  const OutputRelease output;
  const synth::SyntheticScene scene(config);
  synth::writeSequence(scene, out_dir.string(), overwrite);
  return out_dir.string();
}

py::dict run(const std::filesystem::path& sequence, const std::filesystem::path& out_dir,
             const std::optional<SystemConfig>& config, const py::object& frames, const py::object& camera,
             double depth_scale, bool undistort, bool overwrite, bool export_map,
             const std::optional<std::filesystem::path>& map_in) {
  requireExists(sequence, "sequence folder");
  refuseOverlap(out_dir.string(), sequence.string(), "the input sequence");  // as `flowfusion run`
  const SystemConfig c = config.value_or(SystemConfig{});
  const SequenceOptions options = sequenceOptions(camera, depth_scale, undistort);
  const FrameRange range = frameRange(frames);
  RunSummary s;
  {
    py::gil_scoped_release release;
    setOutputCommand("run");
    const OutputRelease output;
    FilesSinkOptions files;
    files.out_dir = out_dir.string();
    files.overwrite = overwrite;
    files.export_map = export_map;
    files.write_clusters = c.pipeline.cluster_log;  // as `flowfusion run --set pipeline.cluster_log=true`
    FilesSink sink(files);
    const std::unique_ptr<FrameSource> source = openFrameSource(sequence.string(), options, range);
    std::optional<SavedMap> map;  // read and checked before anything is written, as `run --map-in`
    if (map_in) map = readMapFor(map_in->string(), out_dir.string(), source->camera(), c.slam);
    RunControl control;
    control.map_in = map ? &*map : nullptr;
    s = runSequence(*source, c, {&sink}, control);
  }
  // summary.json's figures, then what a Python caller needs besides.
  py::dict out = py::module_::import("json").attr("loads")(toJson(s).dump());
  out["trajectory"] = arrayFromTrajectory(s.trajectory);
  out["frame_total_ms"] = py::cast(s.timings.frameTotals());
  out["written"] = py::cast(s.written);
  return out;
}

}  // namespace

void bindTools(py::module_& m) {
  py::module_ e = m.def_submodule("eval", "The metrics of `flowfusion eval`, as dicts like its --json output.");
  e.def("ate", &ate, py::arg("gt"), py::arg("est"), py::arg("max_diff") = 0.02, py::arg("offset") = 0.0,
        "ate(gt, est, max_diff=0.02, offset=0.0) -> dict: absolute trajectory error as the TUM benchmark's "
        "evaluate_ate.py. gt, est: Nx8 arrays (t tx ty tz qx qy qz qw) or TUM trajectory files; offset: seconds "
        "added to est's timestamps first (the scripts' --offset).");
  e.def("rpe", &rpe, py::arg("gt"), py::arg("est"), py::arg("delta") = 1.0, py::arg("offset") = 0.0,
        "rpe(gt, est, delta=1.0, offset=0.0) -> dict: relative pose error over delta seconds, as evaluate_rpe.py "
        "--fixed_delta. gt, est: Nx8 arrays or TUM trajectory files; offset: seconds added to est's timestamps.");
  e.def("seg", &seg, py::arg("gt_masks_dir"), py::arg("est_masks_dir"),
        "seg(gt_masks_dir, est_masks_dir) -> dict: IoU, precision and recall of dynamic masks "
        "(<timestamp>.png, > 127 = dynamic), per frame and pooled.");

  m.def("synth", &synthesise, py::arg("out_dir"), py::arg("seed") = 1, py::arg("frames") = 150,
        py::arg("objects") = 2, py::arg("overwrite") = false,
        "synth(out_dir, seed=1, frames=150, objects=2, overwrite=False, **settings) -> out_dir: a synthetic "
        "dynamic sequence with exact ground truth (poses, masks) in the TUM layout, as `flowfusion synth`. "
        "settings: any other SynthConfig key (width=320, height=240, noise=False, people=1, ...).");
  m.def("run", &run, py::arg("sequence"), py::arg("out_dir"), py::arg("config") = py::none(),
        py::arg("frames") = py::none(), py::arg("camera") = py::none(), py::arg("depth_scale") = 5000.0,
        py::arg("undistort") = true, py::arg("overwrite") = false, py::arg("export_map") = true,
        py::arg("map_in") = py::none(),
        "run(sequence, out_dir, config=None, frames=None, camera=None, depth_scale=5000.0, undistort=True, "
        "overwrite=False, export_map=True, map_in=None) -> dict: `flowfusion run` in-process (the same loop, start "
        "pose and files); the dict holds the trajectory (Nx8) and the run's summary. map_in: a previous run's "
        "folder (or its map.ffmap) to continue in, as `run --map-in`. ValueError, before anything is written, "
        "when out_dir is, contains or lies inside the sequence or map_in, when map_in is not a map this sequence "
        "can continue in, or when another process writes into out_dir.");
}

}  // namespace ff::py_bind
