// The extension module behind the Python package weighted_icp: its docstring, version and error mapping.
#include <pybind11/pybind11.h>

#include "bindings.h"
#include "weighted_icp/io/map_format.h"

namespace py = pybind11;

PYBIND11_MODULE(_weighted_icp, m) {
  m.doc() =
      "weighted_icp: confidence-weighted ICP for sparse landmark maps, the paper's map format, "
      "trajectory errors, the RGB-D SLAM with loop closure and the merging of sessions, with numpy arrays in and out.";
  m.attr("__version__") = WEIGHTED_ICP_MODULE_VERSION;
  // A malformed map is bad input: ValueError, its message naming the file and the line.
  py::register_exception_translator([](std::exception_ptr error) {
    try {
      if (error) std::rethrow_exception(error);
    } catch (const weighted_icp::io::MapFormatError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    }
  });
  weighted_icp::python::bindMaps(m);
  weighted_icp::python::bindRegistration(m);
  weighted_icp::python::bindMetrics(m);
  weighted_icp::python::bindMapping(m);
  weighted_icp::python::bindFrontend(m);
}
