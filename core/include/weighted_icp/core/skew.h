#pragma once
// The cross-product matrix [v]x, with [v]x w = v x w: what every rotation Jacobian and every essential matrix
// is written with, in one place.

#include <Eigen/Core>

namespace weighted_icp {

/// @brief The skew-symmetric matrix [v]x of v, so that [v]x w = v.cross(w).
/// @param v any vector
inline Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

}  // namespace weighted_icp
