// ff.Frame and ff.TumSequence.
#include "sequence.h"

#include <opencv2/imgproc.hpp>
#include <pybind11/stl/filesystem.h>

#include "bindings.h"
#include "convert.h"
#include "flowfusion/pipeline/run.h"

namespace ff::py_bind {

namespace {

TumSequence openSequence(const std::string& path, const SequenceOptions& options) {
  requireExists(path, "sequence folder");
  return TumSequence::open(path, options);
}

// ff.Frame: one frame of a sequence as NumPy arrays.
void bindFrame(py::module_& m) {
  py::class_<PyFrame>(m, "Frame",
                      "One RGB-D frame as a sequence loads it (undistorted when its camera has distortion). "
                      "System.process(frame) is the form that matches `flowfusion run`.")
      .def_property_readonly(
          "rgb",
          [](const PyFrame& f) {
            cv::Mat rgb;
            cv::cvtColor(f.frame.color, rgb, cv::COLOR_BGR2RGB);
            return arrayFromMat(rgb);
          },
          "HxWx3 uint8, RGB.")
      .def_property_readonly("depth", [](const PyFrame& f) { return arrayFromMat(f.frame.depth); },
                             "HxW float32, metres along the optical axis; 0 = no measurement.")
      .def_property_readonly("timestamp", [](const PyFrame& f) { return f.frame.timestamp; },
                             "Seconds, the colour image's time.")
      .def_property_readonly("depth_timestamp", [](const PyFrame& f) { return f.frame.depth_timestamp; },
                             "Seconds, the depth image's time (depth.txt's; up to 20 ms from the colour's in TUM).")
      .def_property_readonly("name", [](const PyFrame& f) { return f.frame.name; }, "The colour image's file.")
      .def("__repr__", [](const PyFrame& f) {
        return "flowfusion.Frame(" + std::to_string(f.frame.timestamp) + ", " + std::to_string(f.frame.width()) + "x" +
               std::to_string(f.frame.height()) + ")";
      });
}

}  // namespace

PySequence::PySequence(const std::string& path, const SequenceOptions& options, FrameRange range)
    : source_(std::make_unique<TumFolderSource>(openSequence(path, options), range)) {
  first_ = static_cast<size_t>(range.first);
  count_ = *source_->remaining();
}

void bindSequence(py::module_& m) {
  bindFrame(m);
  py::class_<PySequence>(m, "TumSequence",
                         "A sequence in the TUM RGB-D layout (rgb.txt, depth.txt, rgb/, depth/, optional "
                         "groundtruth.txt, camera.txt, masks/). len(seq), seq[i] and `for f in seq` give ff.Frame "
                         "objects, loaded (and undistorted) on access.")
      .def(py::init([](const std::filesystem::path& path, const py::object& camera, double depth_scale,
                       bool undistort, const py::object& frames) {
             return std::make_unique<PySequence>(path.string(), sequenceOptions(camera, depth_scale, undistort),
                                                 frameRange(frames));
           }),
           py::arg("path"), py::arg("camera") = py::none(), py::arg("depth_scale") = 5000.0,
           py::arg("undistort") = true, py::arg("frames") = py::none(),
           "TumSequence(path, camera=None, depth_scale=5000.0, undistort=True, frames=None): camera overrides "
           "camera.txt and the folder name (an ff.Camera or a spec 'fr1' or 'fx,fy,cx,cy[,w,h[,k1..k3]]'); "
           "frames='FIRST:LAST' frame indices (inclusive; 'FIRST:' or ':LAST' open). FileNotFoundError when the "
           "folder is missing, ValueError for malformed lists, TypeError for an argument of the wrong type.")
      .def("__len__", &PySequence::size)
      .def(
          "__getitem__",
          [](const PySequence& s, py::ssize_t i) {
            const auto n = static_cast<py::ssize_t>(s.size());
            if (i < 0) i += n;
            if (i < 0 || i >= n) throw py::index_error("frame index out of range");
            py::gil_scoped_release release;
            return s.load(static_cast<size_t>(i));
          },
          py::arg("index"), "Loads frame `index` of the range (PNG decoding releases the GIL).")
      .def_property_readonly(
          "camera", [](const PySequence& s) { return CameraModel{s.sequence().camera(), {}}; },
          "The pinhole camera of the frames this sequence returns (after undistortion).")
      .def_property_readonly(
          "distortion",
          [](const PySequence& s) -> py::object {
            const LensDistortion& d = s.sequence().distortion();
            if (d.none()) return py::none();
            return py::make_tuple(d.k1, d.k2, d.p1, d.p2, d.k3);
          },
          "The raw images' lens distortion (k1, k2, p1, p2, k3), or None.")
      .def_property_readonly(
          "groundtruth",
          [](const PySequence& s) -> py::object {
            if (!s.sequence().groundtruth()) return py::none();
            return arrayFromTrajectory(*s.sequence().groundtruth());
          },
          "groundtruth.txt as an Nx8 float64 array (t tx ty tz qx qy qz qw), or None.")
      .def_property_readonly(
          "masks_dir",
          [](const PySequence& s) -> py::object {
            if (const auto d = s.sequence().masksDir()) return py::str(*d);
            return py::none();
          },
          "The folder of ground-truth dynamic masks (<timestamp>.png), or None.")
      .def_property_readonly("path", [](const PySequence& s) { return s.sequence().dir(); }, "The folder.")
      .def(
          "initial_pose",
          [](const PySequence& s) { return arrayFromPose(initialPose(s.source(), s.timestamp(0))); },
          "4x4 T_world_cam of the first frame as `flowfusion run` starts: the ground truth's pose at its time, "
          "identity without ground truth. Pass it as System(..., T_world_first=...) to reproduce a run.")
      .def(
          "to_raw_pixels",
          [](const PySequence& s, const py::array& image) {
            const int channels = image.ndim() == 3 ? static_cast<int>(image.shape(2)) : 1;
            const CameraIntrinsics& c = s.sequence().camera();
            const cv::Mat m = matFromArray(image, "image", CV_8U, channels, {c.width, c.height});
            return arrayFromMat(s.source().toRawPixels(m));
          },
          py::arg("image"),
          "An HxW (or HxWxC) uint8 image in the frames' pixels (a mask) back in the raw images' pixels, as "
          "`flowfusion run` writes masks; a copy when the frames are not undistorted.");
}

}  // namespace ff::py_bind
