// flowfusion._flowfusion, the extension of the `flowfusion` Python package (python/flowfusion/
// re-exports it): the C++ engine with NumPy arrays in and out (the top README's "Python" section).
// Errors: ff.InputError (a ValueError) for bad data or settings, its message naming the Python
// argument rather than the command-line flag; ValueError naming the argument for arrays of the
// wrong shape, dtype or size, TypeError for an argument of the wrong type; FileNotFoundError for
// missing paths.
#include <pybind11/pybind11.h>

#include "bindings.h"
#include "convert.h"
#include "flowfusion/core/error.h"

namespace py = pybind11;

PYBIND11_MODULE(_flowfusion, m) {
  m.doc() =
      "FlowFusion: dynamic dense RGB-D SLAM (robust dense odometry, optical-flow segmentation of moving "
      "objects, a surfel map of the static scene). NumPy arrays in and out; the C++ engine does the work.\n\n"
      "  cam = flowfusion.Camera.preset('fr1'); cfg = flowfusion.Config(); cfg.set('odometry.levels', 4)\n"
      "  system = flowfusion.System(cam, cfg); r = system.process(rgb, depth, timestamp)\n";
  m.attr("__version__") = FLOWFUSION_VERSION;
  // Leaked on purpose: the translator may run until the interpreter ends (pybind11's advice).
  static auto* input_error = new py::exception<ff::InputError>(m, "InputError", PyExc_ValueError);
  input_error->doc() = "Bad input data or a bad setting (a ValueError); the message names the file or setting.";
  py::register_exception<ff::py_bind::MissingPath>(m, "MissingPathError", PyExc_FileNotFoundError).doc() =
      "A file or folder given as an argument does not exist (a FileNotFoundError).";
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const ff::InputError& e) {
      PyErr_SetString(input_error->ptr(), ff::py_bind::pythonWording(e.what()).c_str());
    } catch (const nlohmann::json::exception& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    }
  });
  ff::py_bind::bindCameraAndConfig(m);
  ff::py_bind::bindSequence(m);
  ff::py_bind::bindSystem(m);
  ff::py_bind::bindTools(m);
}
