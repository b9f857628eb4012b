#pragma once
// Trajectories the io and metrics tests share: a rigid motion from axes and
// angles, a curved camera path, and a path seen from another world frame.

#include <cmath>
#include <cstddef>

#include <Eigen/Geometry>

#include "weighted_icp/core/trajectory.h"

namespace weighted_icp::testing {

/// t + Rz(yaw) Ry(pitch) Rx(roll), angles in radians.
inline Eigen::Isometry3d rigidMotion(double x, double y, double z, double roll, double pitch, double yaw) {
  Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
  motion.linear() =
      (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
       Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
          .toRotationMatrix();
  motion.translation() = Eigen::Vector3d(x, y, z);
  return motion;
}

/// A camera moving along a 3D curve (no three positions collinear) and turning, at 30 Hz.
inline Trajectory curvedTrajectory(std::size_t n) {
  Trajectory trajectory;
  for (std::size_t k = 0; k < n; ++k) {
    const double t = 0.0333 * static_cast<double>(k);
    trajectory.push_back({1305031102.0 + t,
                          rigidMotion(std::cos(t), std::sin(1.3 * t), 0.2 * t, 0.1 * t, -0.05 * t, 0.3 * std::sin(t))});
  }
  return trajectory;
}

/// `trajectory` seen from another world frame: every pose premultiplied by `motion`.
inline Trajectory moved(Trajectory trajectory, const Eigen::Isometry3d& motion) {
  for (auto& stamped : trajectory) stamped.pose = motion * stamped.pose;
  return trajectory;
}

}  // namespace weighted_icp::testing
