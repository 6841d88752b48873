#pragma once
// The parts of the `flowfusion` Python module, each bound in its own file, and the options they share.
#include <pybind11/pybind11.h>

#include "flowfusion/core/output_folder.h"
#include "flowfusion/io/frame_source.h"
#include "flowfusion/io/tum_sequence.h"

namespace ff::py_bind {

namespace py = pybind11;

void bindCameraAndConfig(py::module_& m);  // Camera, Config
void bindSequence(py::module_& m);         // Frame, TumSequence
void bindSystem(py::module_& m);           // Result, System
void bindTools(py::module_& m);            // eval.ate/rpe/seg, synth, run

// Sequence options from the Python arguments: camera None, a spec string ("fr1",
// "fx,fy,cx,cy[,w,h[,k1..k3]]") or an ff.Camera.
SequenceOptions sequenceOptions(const py::object& camera, double depth_scale, bool undistort);
// None (every frame) or "FIRST:LAST" as --frames (TypeError naming `frames` for another type).
FrameRange frameRange(const py::object& frames);

// Releases the output folder (its lock, core/output_folder.h) when System.save or run returns or
// throws, so that the process can write into it again.
struct OutputRelease {
  OutputRelease() = default;
  OutputRelease(const OutputRelease&) = delete;
  OutputRelease& operator=(const OutputRelease&) = delete;
  ~OutputRelease() { releaseOutputDir(); }
};

}  // namespace ff::py_bind
