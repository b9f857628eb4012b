// align(), its result and the weighted correspondence rule for Python, on the same path as wicp_align.
#include <limits>
#include <optional>
#include <string>

#include <pybind11/stl.h>

#include "arrays.h"
#include "bindings.h"
#include "weighted_icp/registration/global_landmark_alignment.h"
#include "weighted_icp/registration/landmark_alignment.h"
#include "weighted_icp/registration/up_axis.h"
#include "weighted_icp/registration/weighted_correspondence_estimation.h"

namespace weighted_icp::python {

namespace {

unsigned int checkedK(int k) {
  if (k < 1 || k > 1000) throw py::value_error("k must be between 1 and 1000 (got " + std::to_string(k) + ")");
  return static_cast<unsigned int>(k);
}

unsigned int checkedThreads(int threads) {
  if (threads < 0 || threads > 1024)
    throw py::value_error("threads must be between 0 (all) and 1024 (got " + std::to_string(threads) + ")");
  return static_cast<unsigned int>(threads);
}

/// The target's weights, from target_weights, or the strategy applied to a LandmarkMap target, or 1 each.
std::vector<double> targetWeights(const py::handle& target, const py::handle& target_weights,
                                  const std::optional<WeightStrategy>& strategy, std::size_t target_points) {
  const bool base = strategy && *strategy == WeightStrategy::Base;
  if (!target_weights.is_none()) {
    if (base) throw py::value_error("strategy 'base' is plain ICP: it takes no target_weights");
    return toWeights(target_weights, "target_weights", target_points);
  }
  if (!strategy || base) return {};
  if (!py::isinstance<LandmarkMap>(target))
    throw py::value_error("strategy '" + toString(*strategy) +
                          "' computes weights from a LandmarkMap target; pass the map, or target_weights");
  return computeWeights(target.cast<const LandmarkMap&>(), weightFunction(*strategy));
}

/// What align() and align_global() share: the ICP's settings, both clouds, the target's weights and the strategy,
/// checked.
struct AlignProblem {
  AlignmentSettings settings;
  std::vector<Eigen::Vector3d> source, target;
  std::vector<double> weights;
  std::optional<WeightStrategy> strategy;
};

AlignProblem alignProblem(const py::object& source, const py::object& target, const py::object& target_weights, int k,
                          const std::optional<std::string>& strategy_name, int max_iterations, int threads) {
  AlignProblem problem;
  std::optional<WeightStrategy>& strategy = problem.strategy;
  if (strategy_name) strategy = parseWeightStrategy(*strategy_name);
  problem.settings.k = strategy ? neighboursFor(*strategy, checkedK(k)) : checkedK(k);
  if (max_iterations < 1)
    throw py::value_error("max_iterations must be >= 1 (got " + std::to_string(max_iterations) + ")");
  problem.settings.max_iterations = max_iterations;
  problem.settings.threads = checkedThreads(threads);
  problem.source = positionsOf(source, "source");
  problem.target = positionsOf(target, "target");
  problem.weights = targetWeights(target, target_weights, strategy, problem.target.size());
  if (problem.source.empty()) throw py::value_error("source has no points");
  if (problem.target.empty()) throw py::value_error("target has no points");
  return problem;
}

AlignmentResult align(const py::object& source, const py::object& target, const py::object& target_weights, int k,
                      const std::optional<std::string>& strategy_name, int max_iterations,
                      const std::optional<double>& max_correspondence_distance, bool refine,
                      const py::object& initial_guess, int threads) {
  AlignProblem problem = alignProblem(source, target, target_weights, k, strategy_name, max_iterations, threads);
  if (max_correspondence_distance) {
    if (!(*max_correspondence_distance > 0.0) || !std::isfinite(*max_correspondence_distance))
      throw py::value_error("max_correspondence_distance must be finite and > 0 (got " +
                            std::to_string(*max_correspondence_distance) + ")");
    problem.settings.max_correspondence_distance = *max_correspondence_distance;
  }
  problem.settings.refine = refine;
  const Eigen::Matrix4d guess =
      initial_guess.is_none() ? Eigen::Matrix4d::Identity() : toMatrix4(initial_guess, "initial_guess");

  py::gil_scoped_release unlocked;
  LandmarkAligner aligner(problem.settings);
  aligner.setTarget(toCloud(problem.target, problem.weights));
  return aligner.align(toCloud(problem.source, {}), guess);
}

/// The axes align_global() levels the maps by: "auto" (both LandmarkMaps: their cameras, chooseUpAxes(); else z),
/// "z", or three numbers for both.
SharedUpAxes upAxesFor(const py::object& up_axis, const py::object& source, const py::object& target) {
  SharedUpAxes axes;
  if (py::isinstance<py::str>(up_axis)) {
    const std::string name = up_axis.cast<std::string>();
    if (name == "z") return axes;
    if (name != "auto") throw py::value_error("up_axis must be 'auto', 'z' or three numbers (got '" + name + "')");
    if (!py::isinstance<LandmarkMap>(source) || !py::isinstance<LandmarkMap>(target)) return axes;
    return chooseUpAxes(estimateUpAxis(source.cast<const LandmarkMap&>().frames),
                        estimateUpAxis(target.cast<const LandmarkMap&>().frames));
  }
  std::vector<double> v;
  try {
    v = up_axis.cast<std::vector<double>>();
  } catch (const py::cast_error&) {
    throw py::value_error("up_axis must be 'auto', 'z' or three numbers");
  }
  const Eigen::Vector3d axis = v.size() == 3 ? Eigen::Vector3d(v[0], v[1], v[2]) : Eigen::Vector3d::Zero();
  if (!axis.allFinite() || !(axis.norm() > 0.0))
    throw py::value_error("up_axis must be three finite numbers, not all zero");
  axes.source = axes.target = axis.normalized();
  return axes;
}

AlignmentResult alignGlobal(const py::object& source, const py::object& target, const py::object& target_weights, int k,
                            const std::optional<std::string>& strategy_name, int max_iterations,
                            const py::object& up_axis, int threads) {
  const SharedUpAxes axes = upAxesFor(up_axis, source, target);
  const AlignProblem problem = alignProblem(source, target, target_weights, k, strategy_name, max_iterations, threads);

  // A source much larger than the target is aligned the other way, weighted by its own weights: the
  // strategy's for a LandmarkMap source, else 1 each (GlobalLandmarkAligner::align).
  const std::vector<double> source_weights =
      py::isinstance<LandmarkMap>(source) ? targetWeights(source, py::none(), problem.strategy, problem.source.size())
                                          : std::vector<double>{};

  py::gil_scoped_release unlocked;
  GlobalAlignmentSettings global;
  global.threads = problem.settings.threads;
  GlobalLandmarkAligner aligner(global, problem.settings);
  aligner.setTarget(toCloud(problem.target, problem.weights));
  return aligner.align(toCloud(problem.source, source_weights), axes).alignment;
}

py::tuple weightedCorrespondences(const py::object& source, const py::object& target, const py::object& weights, int k,
                                  const std::optional<double>& max_distance, int threads) {
  const std::vector<Eigen::Vector3d> source_xyz = positionsOf(source, "source");
  const std::vector<Eigen::Vector3d> target_xyz = positionsOf(target, "target");
  if (target_xyz.empty()) throw py::value_error("target has no points");
  std::vector<double> target_weights = weights.is_none() ? std::vector<double>(target_xyz.size(), 1.0)
                                                         : toWeights(weights, "weights", target_xyz.size());
  if (max_distance && !(*max_distance > 0.0))
    throw py::value_error("max_distance must be > 0 (got " + std::to_string(*max_distance) + ")");
  WeightedCorrespondenceEstimation<LandmarkPoint, LandmarkPoint, double> rule(checkedK(k));
  rule.setNumberOfThreads(checkedThreads(threads));
  rule.setTargetWeights(std::move(target_weights));
  pcl::Correspondences pairs;
  if (!source_xyz.empty()) {
    py::gil_scoped_release unlocked;
    rule.setInputSource(toCloud(source_xyz, {}));
    rule.setInputTarget(toCloud(target_xyz, {}));
    rule.determineCorrespondences(pairs, max_distance.value_or(std::numeric_limits<double>::max()));
  }
  std::vector<std::int64_t> source_index, target_index;
  std::vector<double> squared;
  for (const auto& pair : pairs) {
    source_index.push_back(pair.index_query);
    target_index.push_back(pair.index_match);
    squared.push_back(pair.distance);
  }
  return py::make_tuple(toArray(source_index), toArray(target_index), toArray(squared));
}

}  // namespace

void bindRegistration(py::module_& m) {
  py::class_<AlignmentResult>(m, "AlignmentResult", "What align() found, as wicp_align --json reports it.")
      .def_property_readonly(
          "transformation", [](const AlignmentResult& r) { return toArray(r.transformation); },
          "(4, 4) float64: maps the source (as given) onto the target.")
      .def_readonly("fitness_score", &AlignmentResult::fitness_score,
                    "Mean squared distance from each moved source point to its nearest target point (NaN when "
                    "degenerate).")
      .def_readonly("iterations", &AlignmentResult::iterations, "Iterations of the weighted stage.")
      .def_readonly("refine_iterations", &AlignmentResult::refine_iterations,
                    "Iterations of the nearest-neighbour refinement (0 when refine was off).")
      .def_readonly("converged", &AlignmentResult::converged, "Whether the last stage run converged.")
      .def_readonly("stopped_at_iteration_limit", &AlignmentResult::stopped_at_iteration_limit,
                    "The last stage stopped at its iteration limit before its criteria were met (PCL still "
                    "reports converged).")
      .def_readonly("correspondences", &AlignmentResult::correspondences, "Pairs used by the last iteration.")
      .def_readonly("time_ms", &AlignmentResult::time_ms, "Time of the ICP stages (milliseconds).")
      .def_readonly("degenerate", &AlignmentResult::degenerate,
                    "True when the problem has no unique rigid solution, so ICP was not run.")
      .def_readonly("reason", &AlignmentResult::reason, "Why it is degenerate; empty otherwise.")
      .def("__repr__", [](const AlignmentResult& r) {
        return "<AlignmentResult converged=" + std::string(r.converged ? "True" : "False") +
               " iterations=" + std::to_string(r.iterations) + " fitness_score=" + std::to_string(r.fitness_score) +
               (r.degenerate ? " degenerate: " + r.reason : std::string()) + ">";
      });

  m.def("align", &align, py::arg("source"), py::arg("target"), py::arg("target_weights") = py::none(), py::arg("k") = 5,
        py::arg("strategy") = py::none(), py::arg("max_iterations") = 150,
        py::arg("max_correspondence_distance") = py::none(), py::arg("refine") = false,
        py::arg("initial_guess") = py::none(), py::arg("threads") = 0,
        "Aligns source onto target with the confidence-weighted ICP; the same numbers as wicp_align.\n\n"
        "source, target: (N, 3) float64/float32 arrays or LandmarkMaps.\n"
        "target_weights: (M,) weights of the target points; else strategy's weights of a LandmarkMap target; "
        "else 1 each.\n"
        "strategy: 'base' (plain ICP, k = 1), 'covariance', 'observations', 'mean-distance', or None.\n"
        "The GIL is released while ICP runs.");
  m.def(
      "align_global", &alignGlobal, py::arg("source"), py::arg("target"), py::arg("target_weights") = py::none(),
      py::arg("k") = 5, py::arg("strategy") = py::none(), py::arg("max_iterations") = 150, py::arg("up_axis") = "auto",
      py::arg("threads") = 0,
      "Aligns source onto target from any start, as wicp_align --global: a search over rotations about the up "
      "axis and every translation, partial overlap allowed, then the weighted ICP with its refinement stage.\n\n"
      "source, target, target_weights, k, strategy: as align(). A source much larger than the target (its vote "
      "sample would meet few of the target's) "
      "is aligned the other way (the target onto it, the result inverted), weighted by the strategy's weights of "
      "a LandmarkMap source, else 1 each.\n"
      "up_axis: 'auto' (two LandmarkMaps: z, with tilts up to 16 degrees, when both maps' "
      "cameras are level about it within 8 degrees, else "
      "each map levelled by its own cameras, with tilts, a map whose cameras face about one way also with its "
      "estimate turned 15, 30 and 45 degrees each way about their rows, and z tried as well; arrays: z), 'z', or three "
      "numbers for both maps.\n"
      "The GIL is released while it runs.");
  m.def("weighted_correspondences", &weightedCorrespondences, py::arg("source"), py::arg("target"),
        py::arg("weights") = py::none(), py::arg("k") = 5, py::arg("max_distance") = py::none(), py::arg("threads") = 0,
        "The weighted correspondence rule: for each source point, among its k nearest target points within "
        "max_distance, the heaviest (ties to the nearer).\n\n"
        "Returns (source_idx int64, target_idx int64, sq_dist float64) arrays, one entry per source point that "
        "found a partner.");
}

}  // namespace weighted_icp::python
