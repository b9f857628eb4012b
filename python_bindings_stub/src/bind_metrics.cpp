// ate(), rpe() and compare_ate() for Python: the numbers wicp_evaluate prints, on files or arrays.
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

/// The result types: AbsoluteTrajectoryError, RelativePoseError, AteComparison.
void bindMetricTypes(py::module_& m) {
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

  py::class_<metrics::AteComparison>(m, "AteComparison",
                                     "Two estimates' ATE compared pose by pose (wicp_evaluate --versus).")
      .def_readonly("first", &metrics::AteComparison::first, "The first estimate's ATE over all its pairs.")
      .def_readonly("second", &metrics::AteComparison::second, "The second estimate's ATE over all its pairs.")
      .def_readonly("common_poses", &metrics::AteComparison::common_poses, "Ground-truth poses paired with both.")
      .def_readonly("first_rmse", &metrics::AteComparison::first_rmse_m, "The first's RMSE over the common poses (m).")
      .def_readonly("second_rmse", &metrics::AteComparison::second_rmse_m,
                    "The second's RMSE over the common poses (m).")
      .def_readonly("error_correlation", &metrics::AteComparison::error_correlation,
                    "Pearson correlation of the two per-pose errors.")
      .def_readonly("resamples", &metrics::AteComparison::resamples, "Bootstrap resamples.")
      .def_readonly("first_lower_fraction", &metrics::AteComparison::first_lower_fraction,
                    "Fraction of resamples in which the first's RMSE is the lower (ties count half): near 0.5 no "
                    "difference the poses can show, above 0.95 the first is better beyond the scatter.");
}

/// ate, rpe, compare_ate and the TUM trajectory reader and writer.
void bindMetricFunctions(py::module_& m) {
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
      "compare_ate",
      [](const py::object& groundtruth, const py::object& first, const py::object& second, double max_difference,
         std::size_t resamples) {
        const Trajectory truth = toTrajectory(groundtruth, "gt");
        const Trajectory a = toTrajectory(first, "first");
        const Trajectory b = toTrajectory(second, "second");
        py::gil_scoped_release unlocked;
        return metrics::compareAte(truth, a, b, max_difference, resamples);
      },
      py::arg("gt"), py::arg("first"), py::arg("second"), py::arg("max_difference") = 0.02, py::arg("resamples") = 2000,
      "Is first's ATE lower than second's beyond the scatter of the poses? A paired moving-block bootstrap over the "
      "ground-truth poses both are paired with (deterministic), as wicp_evaluate --versus. Trajectories as ate() "
      "takes them.");
  m.def(
      "read_trajectory", [](const py::object& path) { return toTumRows(toTrajectory(path, "path")); }, py::arg("path"),
      "A TUM trajectory file as an (N, 8) array (timestamp tx ty tz qx qy qz qw); ValueError naming file and line.");
  m.def(
      "write_trajectory",
      [](const py::object& trajectory, const py::object& path) {
        io::writeTrajectory(toTrajectory(trajectory, "trajectory"), toPath(path));
      },
      py::arg("trajectory"), py::arg("path"), "Writes a trajectory (as ate() takes it) in TUM format, atomically.");
}

}  // namespace

void bindMetrics(py::module_& m) {
  bindStatistics(m);
  bindMetricTypes(m);
  bindMetricFunctions(m);
}

}  // namespace weighted_icp::python
