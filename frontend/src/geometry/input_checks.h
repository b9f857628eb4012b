#pragma once
// Input checks shared by the geometry functions (private to this layer).

#include <cmath>
#include <optional>
#include <string>

#include <Eigen/Geometry>

#include "weighted_icp/core/camera.h"

namespace weighted_icp::frontend::detail {

/// Why the intrinsics cannot project, or nothing.
inline std::optional<std::string> cameraProblem(const PinholeCamera& camera) {
  if (!(std::isfinite(camera.fx) && std::isfinite(camera.fy) && camera.fx > 0 && camera.fy > 0 &&
        std::isfinite(camera.cx) && std::isfinite(camera.cy)))
    return "invalid intrinsics: fx=" + std::to_string(camera.fx) + " fy=" + std::to_string(camera.fy) +
           " cx=" + std::to_string(camera.cx) + " cy=" + std::to_string(camera.cy);
  return std::nullopt;
}

/// Finite, with an orthonormal right-handed rotation.
inline bool isRigid(const Eigen::Isometry3d& pose) {
  if (!pose.matrix().allFinite()) return false;
  const Eigen::Matrix3d rotation = pose.linear();
  return (rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).norm() < 1e-6 && rotation.determinant() > 0;
}

}  // namespace weighted_icp::frontend::detail
