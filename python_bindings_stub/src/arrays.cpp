// numpy <-> library conversions for the Python module, with argument-naming ValueErrors.
#include "arrays.h"

#include <cmath>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include <Eigen/Geometry>

#include "weighted_icp/io/trajectory.h"

namespace weighted_icp::python {

namespace {

[[noreturn]] void fail(const std::string& message) { throw py::value_error(message); }

/// A numpy array of float64 or float32 for `handle` (lists are converted, their dtype then checked).
py::array floatArray(const py::handle& handle, const char* name, const char* expected) {
  py::array array = py::array::ensure(handle);
  if (!array)
    fail(std::string(name) + " must be " + expected + " (got " + std::string(py::str(handle.get_type())) + ")");
  if (!array.dtype().is(py::dtype::of<double>()) && !array.dtype().is(py::dtype::of<float>()))
    fail(std::string(name) + " must be " + expected + " of float64 or float32 (got dtype " +
         std::string(py::str(array.dtype())) + ")");
  return array;
}

std::string shapeText(const py::array& array) {
  std::ostringstream out;
  out << '(';
  for (py::ssize_t d = 0; d < array.ndim(); ++d) out << (d ? ", " : "") << array.shape(d);
  out << (array.ndim() == 1 ? ",)" : ")");
  return out.str();
}

/// Element (i, j) of a 2-D float array of either dtype, by strides: no copy of the array.
double at2(const py::array& array, py::ssize_t i, py::ssize_t j) {
  const char* p = static_cast<const char*>(array.data()) + i * array.strides(0) + j * array.strides(1);
  return array.dtype().is(py::dtype::of<double>()) ? *reinterpret_cast<const double*>(p)
                                                   : *reinterpret_cast<const float*>(p);
}

double at1(const py::array& array, py::ssize_t i) {
  const char* p = static_cast<const char*>(array.data()) + i * array.strides(0);
  return array.dtype().is(py::dtype::of<double>()) ? *reinterpret_cast<const double*>(p)
                                                   : *reinterpret_cast<const float*>(p);
}

}  // namespace

std::vector<Eigen::Vector3d> toPositions(const py::handle& points, const char* name) {
  const py::array array = floatArray(points, name, "an (N, 3) array");
  if (array.ndim() != 2 || array.shape(1) != 3)
    fail(std::string(name) + " must have shape (N, 3) (got " + shapeText(array) + ")");
  std::vector<Eigen::Vector3d> positions(static_cast<std::size_t>(array.shape(0)));
  for (py::ssize_t i = 0; i < array.shape(0); ++i)
    positions[static_cast<std::size_t>(i)] = Eigen::Vector3d(at2(array, i, 0), at2(array, i, 1), at2(array, i, 2));
  return positions;
}

std::vector<Eigen::Vector3d> positionsOf(const py::handle& points, const char* name) {
  if (py::isinstance<LandmarkMap>(points)) {
    const auto& map = points.cast<const LandmarkMap&>();
    std::vector<Eigen::Vector3d> positions;
    positions.reserve(map.landmarks.size());
    for (const auto& landmark : map.landmarks) positions.push_back(landmark.position);
    return positions;
  }
  return toPositions(points, name);
}

std::vector<double> toWeights(const py::handle& values, const char* name, std::size_t expected) {
  const py::array array = floatArray(values, name, "a 1-D array");
  if (array.ndim() != 1 || static_cast<std::size_t>(array.shape(0)) != expected)
    fail(std::string(name) + " must have shape (" + std::to_string(expected) + ",), one per target point (got " +
         shapeText(array) + ")");
  std::vector<double> weights(expected);
  for (std::size_t i = 0; i < expected; ++i) {
    weights[i] = at1(array, static_cast<py::ssize_t>(i));
    if (!std::isfinite(weights[i]) || weights[i] < 0.0)
      fail(std::string(name) + "[" + std::to_string(i) + "] is " + std::to_string(weights[i]) +
           "; weights must be finite and >= 0");
  }
  return weights;
}

Eigen::Matrix4d toMatrix4(const py::handle& matrix, const char* name) {
  const py::array array = floatArray(matrix, name, "a (4, 4) array");
  if (array.ndim() != 2 || array.shape(0) != 4 || array.shape(1) != 4)
    fail(std::string(name) + " must have shape (4, 4) (got " + shapeText(array) + ")");
  Eigen::Matrix4d out;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) {
      out(r, c) = at2(array, r, c);
      if (!std::isfinite(out(r, c))) fail(std::string(name) + " has a non-finite entry");
    }
  return out;
}

LandmarkCloud::Ptr toCloud(const std::vector<Eigen::Vector3d>& positions, const std::vector<double>& weights) {
  auto cloud = std::make_shared<LandmarkCloud>();
  cloud->reserve(positions.size());
  for (std::size_t i = 0; i < positions.size(); ++i) {
    LandmarkPoint p{};
    // As toLandmarkCloud() rounds a map's positions, so both paths give wicp_align's numbers.
    p.x = static_cast<float>(positions[i].x());
    p.y = static_cast<float>(positions[i].y());
    p.z = static_cast<float>(positions[i].z());
    p.data[3] = 1.0f;
    p.weight = weights.empty() ? 1.0 : weights[i];
    cloud->push_back(p);
  }
  return cloud;
}

py::array_t<double> toArray(const Eigen::MatrixXd& matrix) {
  py::array_t<double> out({matrix.rows(), matrix.cols()});
  auto view = out.mutable_unchecked<2>();
  for (Eigen::Index r = 0; r < matrix.rows(); ++r)
    for (Eigen::Index c = 0; c < matrix.cols(); ++c) view(r, c) = matrix(r, c);
  return out;
}

namespace {

Trajectory fromTumRows(const py::array& rows, const char* name) {
  if (rows.ndim() != 2 || rows.shape(1) != 8)
    fail(std::string(name) + " must have shape (N, 8): timestamp tx ty tz qx qy qz qw (got " + shapeText(rows) + ")");
  Trajectory trajectory;
  for (py::ssize_t i = 0; i < rows.shape(0); ++i) {
    const Eigen::Quaterniond q(at2(rows, i, 7), at2(rows, i, 4), at2(rows, i, 5), at2(rows, i, 6));
    // As io::readTrajectory: a quaternion far from unit norm is a wrong row, not rounding.
    if (!(std::abs(q.norm() - 1.0) <= 1e-2))
      fail(std::string(name) + " row " + std::to_string(i) + ": quaternion (qx qy qz qw) has norm " +
           std::to_string(q.norm()) + "; expected 1");
    StampedPose stamped;
    stamped.timestamp = at2(rows, i, 0);
    stamped.pose.linear() = q.normalized().toRotationMatrix();
    stamped.pose.translation() = Eigen::Vector3d(at2(rows, i, 1), at2(rows, i, 2), at2(rows, i, 3));
    trajectory.push_back(stamped);
  }
  return trajectory;
}

Trajectory fromPoses(const py::handle& timestamps, const py::handle& poses, const char* name) {
  const std::string stamps_name = std::string(name) + "[0] (timestamps)";
  const std::string poses_name = std::string(name) + "[1] (poses)";
  const py::array stamps = floatArray(timestamps, stamps_name.c_str(), "a 1-D array");
  const py::array matrices = floatArray(poses, poses_name.c_str(), "an (N, 4, 4) array");
  if (stamps.ndim() != 1) fail(stamps_name + " must be 1-D (got " + shapeText(stamps) + ")");
  if (matrices.ndim() != 3 || matrices.shape(0) != stamps.shape(0) || matrices.shape(1) != 4 || matrices.shape(2) != 4)
    fail(poses_name + " must have shape (" + std::to_string(stamps.shape(0)) + ", 4, 4) (got " + shapeText(matrices) +
         ")");
  const py::array_t<double, py::array::forcecast> m = py::array_t<double, py::array::forcecast>::ensure(matrices);
  const auto view = m.unchecked<3>();
  Trajectory trajectory;
  for (py::ssize_t i = 0; i < stamps.shape(0); ++i) {
    StampedPose stamped;
    stamped.timestamp = at1(stamps, i);
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) stamped.pose.matrix()(r, c) = view(i, r, c);
    trajectory.push_back(stamped);
  }
  return trajectory;
}

}  // namespace

std::string toPath(const py::handle& path_like) { return py::str(py::module_::import("os").attr("fspath")(path_like)); }

std::string existingPath(const py::handle& path_like) {
  const std::string path = toPath(path_like);
  if (!std::filesystem::exists(path)) {
    PyErr_SetFromErrnoWithFilename(PyExc_FileNotFoundError, path.c_str());
    throw py::error_already_set();
  }
  return path;
}

Trajectory toTrajectory(const py::handle& trajectory, const char* name) {
  if (py::isinstance<py::str>(trajectory) || py::hasattr(trajectory, "__fspath__")) {
    const std::string path = toPath(trajectory);
    try {
      return io::readTrajectory(path);
    } catch (const std::runtime_error& e) {
      fail(e.what());
    }
  }
  if (py::isinstance<py::tuple>(trajectory) && py::len(trajectory) == 2) {
    const py::tuple pair = trajectory.cast<py::tuple>();
    return fromPoses(pair[0], pair[1], name);
  }
  const std::string expected = "a TUM file path, an (N, 8) array or a (timestamps, poses) pair; got";
  if (!py::isinstance<py::array>(trajectory) && !py::isinstance<py::list>(trajectory))
    fail(std::string(name) + " must be " + expected + " " + std::string(py::str(trajectory.get_type())));
  return fromTumRows(floatArray(trajectory, name, "an (N, 8) array"), name);
}

py::array_t<double> toTumRows(const Trajectory& trajectory) {
  py::array_t<double> out({static_cast<py::ssize_t>(trajectory.size()), py::ssize_t{8}});
  auto view = out.mutable_unchecked<2>();
  for (std::size_t i = 0; i < trajectory.size(); ++i) {
    const auto& [timestamp, pose] = trajectory[i];
    const Eigen::Quaterniond q(pose.linear());
    const Eigen::Vector3d& t = pose.translation();
    const double row[8] = {timestamp, t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()};
    for (int c = 0; c < 8; ++c) view(static_cast<py::ssize_t>(i), c) = row[c];
  }
  return out;
}

}  // namespace weighted_icp::python
