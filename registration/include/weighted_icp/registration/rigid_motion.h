#pragma once
// Rigid motions as the paper's experiments state them, and their errors.

#include <string>

#include <Eigen/Geometry>

namespace weighted_icp {

/// A displacement in metres and degrees, applied as t + Rz(yaw)·Ry(pitch)·Rx(roll).
struct Displacement {
  double x = 0.0, y = 0.0, z = 0.0;
  double roll_deg = 0.0, pitch_deg = 0.0, yaw_deg = 0.0;

  Eigen::Isometry3d toIsometry() const;
  /// Parses "x y z roll pitch yaw"; throws std::invalid_argument saying what is wrong.
  static Displacement parse(const std::string& text);
  std::string toString() const;
};

/// The inverse of a rigid transformation (rotation and translation) as a 4x4 matrix.
Eigen::Matrix4d inverseRigid(const Eigen::Matrix4d& transformation);
/// Angle of the rotation that takes `estimate` to `truth`, in degrees.
double rotationErrorDeg(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& truth);
/// Distance between the translations of `estimate` and `truth`, in metres.
double translationError(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& truth);

}  // namespace weighted_icp
