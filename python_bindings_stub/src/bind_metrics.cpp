// ate() and rpe() for Python: the numbers wicp_evaluate prints, on files or arrays.
#include <pybind11/stl.h>

#include "arrays.h"
#include "bindings.h"
#include "weighted_icp/io/trajectory.h"
#include "weighted_icp/metrics/trajectory_error.h"

namespace weighted_icp::python {

namespace {

void bindStatistics(py::module_& m) {
  py::class_<ErrorStatistics>(m, "ErrorStatistics", "RMSE, mean, median and maximum of a set of errors.")
      .def_readonly("rmse", &ErrorStatistics::rmse, "Root mean square.")
      .def_readonly("mean", &ErrorStatistics::mean, "Mean.")
      .def_readonly("median", &ErrorStatistics::median, "Median.")
      .def_readonly("max", &ErrorStatistics::max, "Maximum.")
      .def("__repr__", [](const ErrorStatistics& s) {
        return "<ErrorStatistics rmse=" + std::to_string(s.rmse) + " mean=" + std::to_string(s.mean) +
               " median=" + std::to_string(s.median) + " max=" + std::to_string(s.max) + ">";
      });
}

}  // namespace

void bindMetrics(py::module_& m) {
  bindStatistics(m);
  py::class_<metrics::AbsoluteTrajectoryError>(m, "AbsoluteTrajectoryError",
                                               "The ATE as evaluate_ate.py computes it (wicp_evaluate's ate_*).")
      .def_readonly("pairs", &metrics::AbsoluteTrajectoryError::pairs, "Associated (ground truth, estimate) poses.")
      .def_readonly("translation", &metrics::AbsoluteTrajectoryError::translation,
                    "Position errors after alignment (metres).")
      .def_property_readonly(
          "rmse", [](const metrics::AbsoluteTrajectoryError& a) { return a.translation.rmse; },
          "translation.rmse (metres).")
      .def_property_readonly(
          "alignment", [](const metrics::AbsoluteTrajectoryError& a) { return toArray(a.alignment.matrix()); },
          "(4, 4) float64: the rigid motion mapping the estimate onto the ground truth.");
  py::class_<metrics::RelativePoseError>(
      m, "RelativePoseError", "The RPE as evaluate_rpe.py --fixed_delta computes it (wicp_evaluate's rpe_*).")
      .def_readonly("pairs", &metrics::RelativePoseError::pairs, "Compared pose pairs.")
      .def_readonly("translation", &metrics::RelativePoseError::translation, "Translation errors (metres).")
      .def_readonly("rotation_deg", &metrics::RelativePoseError::rotation_deg, "Rotation errors (degrees).");

  m.def(
      "ate",
      [](const py::object& groundtruth, const py::object& estimate, double max_difference) {
        const Trajectory truth = toTrajectory(groundtruth, "gt");
        const Trajectory est = toTrajectory(estimate, "est");
        py::gil_scoped_release unlocked;
        return metrics::computeAte(truth, est, max_difference);
      },
      py::arg("gt"), py::arg("est"), py::arg("max_difference") = 0.02,
      "Absolute trajectory error of est against gt, as wicp_evaluate.\n\n"
      "Each trajectory is a TUM file path, an (N, 8) array of rows 'timestamp tx ty tz qx qy qz qw', or a "
      "(timestamps (N,), poses (N, 4, 4)) pair. Poses pair up when their timestamps differ by less than "
      "max_difference seconds.");
  m.def(
      "rpe",
      [](const py::object& groundtruth, const py::object& estimate, double delta, const std::string& unit) {
        if (unit != "s" && unit != "f")
          throw py::value_error("unit must be 's' (seconds) or 'f' (frames), got '" + unit + "'");
        const Trajectory truth = toTrajectory(groundtruth, "gt");
        const Trajectory est = toTrajectory(estimate, "est");
        py::gil_scoped_release unlocked;
        return metrics::computeRpe(truth, est, delta,
                                   unit == "s" ? metrics::DeltaUnit::Seconds : metrics::DeltaUnit::Frames);
      },
      py::arg("gt"), py::arg("est"), py::arg("delta") = 1.0, py::arg("unit") = "s",
      "Relative pose error over pose pairs delta apart (unit 's' seconds or 'f' frames), as wicp_evaluate.");
  m.def(
      "read_trajectory", [](const py::object& path) { return toTumRows(toTrajectory(path, "path")); }, py::arg("path"),
      "A TUM trajectory file as an (N, 8) array (timestamp tx ty tz qx qy qz qw); ValueError naming file and line.");
  m.def(
      "write_trajectory",
      [](const py::object& trajectory, const py::object& path) {
        io::writeTrajectory(toTrajectory(trajectory, "trajectory"),
                            py::str(py::module_::import("os").attr("fspath")(path)));
      },
      py::arg("trajectory"), py::arg("path"), "Writes a trajectory (as ate() takes it) in TUM format, atomically.");
}

}  // namespace weighted_icp::python
