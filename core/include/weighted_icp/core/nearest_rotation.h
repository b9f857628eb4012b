#pragma once
// Poses composed many times (loop corrections on top of bundle adjustments on top of tracking) drift from a rigid
// motion by floating-point rounding: their rotation matrices stop being exactly orthonormal (1e-8 after a hundred
// keyframes of corrections, measured). The nearest rotation puts them back, so that what is written as a unit
// quaternion is the pose that was meant.

#include <Eigen/Geometry>

namespace weighted_icp {

/// @brief The pose with its rotation replaced by the nearest rotation (through a normalised quaternion, exact to
/// first order for a rotation that is nearly orthonormal); the translation is kept.
/// @param pose a pose whose linear part is a rotation up to rounding
inline Eigen::Isometry3d withNearestRotation(const Eigen::Isometry3d& pose) {
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = Eigen::Quaterniond(Eigen::Matrix3d(pose.linear())).normalized().toRotationMatrix();
  out.translation() = pose.translation();
  return out;
}

}  // namespace weighted_icp
