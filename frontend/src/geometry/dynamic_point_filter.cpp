#include "weighted_icp/frontend/geometry/dynamic_point_filter.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "input_checks.h"
#include "weighted_icp/core/skew.h"

namespace weighted_icp::frontend {

namespace {

constexpr double kNoDistance = std::numeric_limits<double>::quiet_NaN();

template <typename A, typename B>
void requireSameSize(const A& a, const B& b, const char* function) {
  if (a.size() != b.size())
    throw std::invalid_argument(std::string(function) + ": " + std::to_string(a.size()) + " and " +
                                std::to_string(b.size()) + " matches");
}

}  // namespace

std::vector<double> displacementDistances(const std::vector<Eigen::Vector3d>& points_world,
                                          const std::vector<Eigen::Vector3d>& points_camera_measured,
                                          const Eigen::Isometry3d& pose_wc) {
  requireSameSize(points_world, points_camera_measured, "displacementDistances");
  std::vector<double> distances(points_world.size(), kNoDistance);
  if (!pose_wc.matrix().allFinite()) return distances;
  const Eigen::Isometry3d pose_cw = pose_wc.inverse();
  for (std::size_t i = 0; i < points_world.size(); ++i) {
    const Eigen::Vector3d& measured = points_camera_measured[i];
    if (!points_world[i].allFinite() || !measured.allFinite() || !(measured.z() > 0)) continue;
    distances[i] = (pose_cw * points_world[i] - measured).norm();
  }
  return distances;
}

std::vector<bool> flagDynamicByDisplacement(const std::vector<Eigen::Vector3d>& points_world,
                                            const std::vector<Eigen::Vector3d>& points_camera_measured,
                                            const Eigen::Isometry3d& pose_wc, const DepthNoiseModel& noise,
                                            const DynamicPointFilterOptions& options) {
  const std::vector<double> distances = displacementDistances(points_world, points_camera_measured, pose_wc);
  std::vector<bool> flags(distances.size(), false);
  for (std::size_t i = 0; i < distances.size(); ++i) {
    if (std::isnan(distances[i])) continue;
    const double threshold =
        std::max(options.min_displacement_m, options.depth_sigmas * noise.sigmaDepth(points_camera_measured[i].z()));
    flags[i] = distances[i] > threshold;
  }
  return flags;
}

Eigen::Matrix3d fundamentalMatrix(const Eigen::Isometry3d& pose_2_in_1, const PinholeCamera& camera) {
  const Eigen::Isometry3d pose_21 = pose_2_in_1.inverse();  // x2 = R x1 + t
  if (!(pose_21.translation().norm() >= 1e-12)) return Eigen::Matrix3d::Zero();
  const Eigen::Matrix3d camera_inverse = camera.intrinsicMatrix().inverse();
  return camera_inverse.transpose() * skew(pose_21.translation().normalized()) * pose_21.linear() * camera_inverse;
}

double distanceToLine(const Eigen::Vector3d& line, const Eigen::Vector2d& pixel) {
  const double norm = line.head<2>().norm();
  if (!(norm > 0.0)) return std::numeric_limits<double>::quiet_NaN();
  return std::abs(line.dot(pixel.homogeneous())) / norm;
}

std::vector<double> symmetricEpipolarDistances(const std::vector<Eigen::Vector2d>& pixels1,
                                               const std::vector<Eigen::Vector2d>& pixels2,
                                               const Eigen::Isometry3d& pose_2_in_1, const PinholeCamera& camera) {
  requireSameSize(pixels1, pixels2, "symmetricEpipolarDistances");
  if (const auto problem = detail::cameraProblem(camera))
    throw std::invalid_argument("symmetricEpipolarDistances: " + *problem);
  std::vector<double> distances(pixels1.size(), kNoDistance);
  const Eigen::Isometry3d pose_21 = pose_2_in_1.inverse();  // x2 = R x1 + t
  if (!pose_21.matrix().allFinite() || pose_21.translation().norm() < 1e-12) return distances;

  const Eigen::Matrix3d fundamental = fundamentalMatrix(pose_2_in_1, camera);
  for (std::size_t i = 0; i < pixels1.size(); ++i) {
    if (!pixels1[i].allFinite() || !pixels2[i].allFinite()) continue;
    const double d2 = distanceToLine(fundamental * pixels1[i].homogeneous(), pixels2[i]);
    const double d1 = distanceToLine(fundamental.transpose() * pixels2[i].homogeneous(), pixels1[i]);
    distances[i] = std::sqrt(0.5 * (d1 * d1 + d2 * d2));
  }
  return distances;
}

std::vector<bool> flagDynamicByEpipolarDistance(const std::vector<Eigen::Vector2d>& pixels1,
                                                const std::vector<Eigen::Vector2d>& pixels2,
                                                const Eigen::Isometry3d& pose_2_in_1, const PinholeCamera& camera,
                                                const DynamicPointFilterOptions& options) {
  const std::vector<double> distances = symmetricEpipolarDistances(pixels1, pixels2, pose_2_in_1, camera);
  std::vector<bool> flags(distances.size(), false);
  for (std::size_t i = 0; i < distances.size(); ++i) flags[i] = distances[i] > options.max_epipolar_px;  // NaN: false
  return flags;
}

}  // namespace weighted_icp::frontend
