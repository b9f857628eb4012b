#pragma once
// Conversions between numpy arrays and the library's types for the Python module; every check names the
// Python argument it reads, so a wrong shape or dtype reads "source must be ..." rather than a C++ message.

#include <cstddef>
#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <Eigen/Core>

#include "weighted_icp/core/trajectory.h"
#include "weighted_icp/registration/landmark_map.h"
#include "weighted_icp/registration/landmark_point.h"

namespace weighted_icp::python {

namespace py = pybind11;

/// @brief Positions from an (N, 3) float64 or float32 array (any strides: read in place, not copied first).
/// @param points  the Python object; anything else (shape, dtype, a non-array) raises ValueError naming `name`
/// @param name    the argument's name, for the error
std::vector<Eigen::Vector3d> toPositions(const py::handle& points, const char* name);

/// @brief The positions of a LandmarkMap or an (N, 3) array, as toPositions().
/// @param points  a LandmarkMap or an array
/// @param name    the argument's name, for errors
std::vector<Eigen::Vector3d> positionsOf(const py::handle& points, const char* name);

/// @brief A 1-D float array of `expected` finite values >= 0 (weights); ValueError naming `name` and the index.
/// @param values    float64 or float32, shape (expected,)
/// @param name      the argument's name, for errors
/// @param expected  the length it must have
std::vector<double> toWeights(const py::handle& values, const char* name, std::size_t expected);

/// @brief A 4x4 float array as a matrix; ValueError naming `name` for another shape or a non-finite entry.
/// @param matrix  float64 or float32, shape (4, 4)
/// @param name    the argument's name, for errors
Eigen::Matrix4d toMatrix4(const py::handle& matrix, const char* name);

/// @brief The landmark cloud the aligner takes: positions as floats (as toLandmarkCloud() rounds them) and weights.
/// @param positions  the points
/// @param weights    one per point, or empty for 1 each
LandmarkCloud::Ptr toCloud(const std::vector<Eigen::Vector3d>& positions, const std::vector<double>& weights);

/// @brief A new float64 array holding `matrix` (row-major, as numpy shows it).
/// @param matrix  any size
py::array_t<double> toArray(const Eigen::MatrixXd& matrix);

/// @brief A new 1-D array of the values.
/// @param values  copied
template <typename T>
py::array_t<T> toArray(const std::vector<T>& values) {
  py::array_t<T> out(static_cast<py::ssize_t>(values.size()));
  std::copy(values.begin(), values.end(), out.mutable_data());
  return out;
}

/// @brief A trajectory from a TUM file path, an (N, 8) array of TUM rows (t tx ty tz qx qy qz qw) or a
/// (timestamps (N,), poses (N, 4, 4)) pair; ValueError naming `name` otherwise.
/// @param trajectory  the Python object
/// @param name        the argument's name, for errors
Trajectory toTrajectory(const py::handle& trajectory, const char* name);

/// @brief The path a str or an os.PathLike names (os.fspath).
/// @param path_like  the Python object
std::string toPath(const py::handle& path_like);

/// @brief toPath(), raising Python's FileNotFoundError naming the path when nothing is there: a missing file is
/// not malformed input.
/// @param path_like  the Python object
std::string existingPath(const py::handle& path_like);

/// @brief TUM rows (N, 8): timestamp tx ty tz qx qy qz qw, one per pose.
/// @param trajectory  the poses
py::array_t<double> toTumRows(const Trajectory& trajectory);

}  // namespace weighted_icp::python
