// LandmarkMap and the weight strategies for Python: the paper's map format in, numpy arrays out.
#include <string>

#include <pybind11/stl.h>

#include "arrays.h"
#include "bindings.h"
#include "weighted_icp/io/map_format.h"
#include "weighted_icp/registration/weight_strategies.h"

namespace weighted_icp::python {

namespace {

LandmarkMap loadMap(const py::object& path_like, std::size_t min_observations) {
  const std::string path = existingPath(path_like);
  LandmarkMap map;
  {
    py::gil_scoped_release unlocked;  // large maps take a while to parse
    map = io::readLandmarkMap(path).withMinObservations(min_observations);
  }
  return map;
}

py::array_t<double> positions(const LandmarkMap& map) {
  py::array_t<double> out({static_cast<py::ssize_t>(map.landmarks.size()), py::ssize_t{3}});
  auto view = out.mutable_unchecked<2>();
  for (std::size_t i = 0; i < map.landmarks.size(); ++i)
    for (int c = 0; c < 3; ++c) view(static_cast<py::ssize_t>(i), c) = map.landmarks[i].position[c];
  return out;
}

py::array_t<double> covariances(const LandmarkMap& map) {
  py::array_t<double> out({static_cast<py::ssize_t>(map.landmarks.size()), py::ssize_t{3}, py::ssize_t{3}});
  auto view = out.mutable_unchecked<3>();
  for (std::size_t i = 0; i < map.landmarks.size(); ++i)
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) view(static_cast<py::ssize_t>(i), r, c) = map.landmarks[i].covariance(r, c);
  return out;
}

template <typename T, typename Get>
py::array_t<T> perLandmark(const LandmarkMap& map, Get get) {
  std::vector<T> values;
  values.reserve(map.landmarks.size());
  for (const auto& landmark : map.landmarks) values.push_back(static_cast<T>(get(landmark)));
  return toArray(values);
}

py::dict frames(const LandmarkMap& map) {
  py::dict out;
  for (const auto& [id, pose] : map.frames) out[py::int_(id)] = toArray(pose.matrix());
  return out;
}

/// A map of bare points (no frames, no observations): the way into the map API for any cloud.
LandmarkMap fromPositions(const py::handle& points, const py::object& covariance_array) {
  const std::vector<Eigen::Vector3d> xyz = toPositions(points, "positions");
  LandmarkMap map;
  map.landmarks.resize(xyz.size());
  const bool has_covariances = !covariance_array.is_none();
  py::array_t<double, py::array::forcecast> cov;
  if (has_covariances) {
    cov = py::array_t<double, py::array::forcecast>::ensure(covariance_array);
    if (!cov || cov.ndim() != 3 || static_cast<std::size_t>(cov.shape(0)) != xyz.size() || cov.shape(1) != 3 ||
        cov.shape(2) != 3)
      throw py::value_error("covariances must have shape (" + std::to_string(xyz.size()) + ", 3, 3)");
  }
  for (std::size_t i = 0; i < xyz.size(); ++i) {
    map.landmarks[i].id = i;
    map.landmarks[i].position = xyz[i];
    if (!has_covariances) continue;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) map.landmarks[i].covariance(r, c) = cov.at(static_cast<py::ssize_t>(i), r, c);
  }
  return map;
}

void transformMap(LandmarkMap& map, const py::handle& matrix) {
  const Eigen::Matrix4d m = toMatrix4(matrix, "matrix");
  const Eigen::Matrix3d r = m.topLeftCorner<3, 3>();
  if (!(r.transpose() * r).isIdentity(1e-6) || r.determinant() < 0.0 ||
      !m.row(3).isApprox(Eigen::RowVector4d(0, 0, 0, 1)))
    throw py::value_error("matrix must be a rigid motion (rotation and translation, last row 0 0 0 1)");
  Eigen::Isometry3d motion(m);
  map.transform(motion);
}

using MapClass = py::class_<LandmarkMap, std::shared_ptr<LandmarkMap>>;

/// LandmarkMap's per-landmark and per-frame arrays.
void addMapArrays(MapClass& map_class) {
  map_class.def_property_readonly("positions", &positions, "(N, 3) float64: landmark positions (world).")
      .def_property_readonly("covariances", &covariances, "(N, 3, 3) float64: position covariances.")
      .def_property_readonly(
          "observation_counts",
          [](const LandmarkMap& map) {
            return perLandmark<std::int64_t>(map, [](const Landmark& l) { return l.observations.size(); });
          },
          "(N,) int64: how many times each landmark was observed.")
      .def_property_readonly(
          "ids",
          [](const LandmarkMap& map) {
            return perLandmark<std::uint64_t>(map, [](const Landmark& l) { return l.id; });
          },
          "(N,) uint64: landmark ids.")
      .def_property_readonly(
          "mean_observation_distances",
          [](const LandmarkMap& map) {
            return perLandmark<double>(map, [&](const Landmark& l) { return map.meanObservationDistance(l); });
          },
          "(N,) float64: mean distance from each landmark to the cameras that observed it (0 when unobserved).")
      .def_property_readonly("frames", &frames, "{frame id: (4, 4) float64 camera-to-world pose}, by frame id.")
      .def_property_readonly(
          "frame_ids",
          [](const LandmarkMap& map) {
            std::vector<std::uint64_t> ids;
            for (const auto& frame : map.frames) ids.push_back(frame.first);
            return toArray(ids);
          },
          "(F,) uint64: frame ids, ascending.");
}

/// LandmarkMap's operations that make other maps or move this one.
void addMapOperations(MapClass& map_class) {
  map_class
      .def("with_min_observations", &LandmarkMap::withMinObservations, py::arg("min_observations"),
           "The landmarks observed at least min_observations times; frames kept.")
      .def("mini_map", &LandmarkMap::miniMap, py::arg("first"), py::arg("last"),
           "The mini-map of frames [first, last]: those frames and the landmarks they saw, with only "
           "their observations.")
      .def("split_into_mini_maps", &LandmarkMap::splitIntoMiniMaps, py::arg("frames_per_minimap"),
           "Consecutive mini-maps of frames_per_minimap frames each, in frame-id order.")
      .def("alternate_halves", &LandmarkMap::alternateHalves,
           "Two maps with every frame and alternate landmarks: disjoint point sets whose true relation is the "
           "identity.")
      .def("transform", &transformMap, py::arg("matrix"),
           "Moves the map in place by a (4, 4) rigid motion: frame poses, positions, covariances.");
}

/// The weight functions over a map, by strategy name.
void bindWeights(py::module_& m) {
  m.def(
      "weights",
      [](const LandmarkMap& map, const std::string& strategy) {
        return toArray(computeWeights(map, weightFunction(parseWeightStrategy(strategy))));
      },
      py::arg("map"), py::arg("strategy"),
      "(N,) float64: one weight per landmark with a built-in strategy: 'base' (1 each), 'covariance' "
      "(1 / (1 + ||Cov||_F)), 'observations' (the count), 'mean-distance' (1 / (1 + mean camera distance)). "
      "Raises ValueError for another name.");
  m.def(
      "strategies",
      [] {
        std::vector<std::string> names;
        for (const WeightStrategy s : allWeightStrategies()) names.push_back(toString(s));
        return names;
      },
      "The weight strategies' names, as weights() and align() take them.");
}

}  // namespace

void bindMaps(py::module_& m) {
  MapClass map_class(m, "LandmarkMap",
                     "A landmark map in the paper's model: frame poses and, per "
                     "landmark, position, covariance and observations.\n\n"
                     "The array properties are new arrays on every access.");
  map_class.def(py::init<>(), "An empty map.")
      .def_static("load", &loadMap, py::arg("path"), py::arg("min_observations") = 0,
                  "Reads a map in the paper's format (FRAME / LANDMARK lines).\n\n"
                  "min_observations drops landmarks seen fewer times (wicp_align's default is 2, this "
                  "function's 0 keeps the file as it is). Raises ValueError naming the file and line for a "
                  "malformed file, FileNotFoundError when there is none.")
      .def_static("from_positions", &fromPositions, py::arg("positions"), py::arg("covariances") = py::none(),
                  "A map of bare landmarks (ids 0..N-1, no frames, no observations) from an (N, 3) array and "
                  "optional (N, 3, 3) covariances.")
      .def(
          "save", [](const LandmarkMap& map, const py::object& path) { io::writeLandmarkMap(map, toPath(path)); },
          py::arg("path"), "Writes the map in the paper's format, atomically (a temporary file, then a rename).")
      .def(
          "copy", [](const LandmarkMap& map) { return LandmarkMap(map); }, "An independent copy.")
      .def(
          "__len__", [](const LandmarkMap& map) { return map.landmarks.size(); }, "The number of landmarks.")
      .def("__repr__", [](const LandmarkMap& map) {
        return "<LandmarkMap: " + std::to_string(map.landmarks.size()) + " landmarks, " +
               std::to_string(map.frames.size()) + " frames>";
      });
  addMapArrays(map_class);
  addMapOperations(map_class);
  bindWeights(m);
}

}  // namespace weighted_icp::python
