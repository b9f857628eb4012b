#pragma once
// A trajectory: camera-to-world poses with timestamps, as the front end
// estimates it, the simulator knows it and the metrics compare it. Its TUM
// text format is io's (weighted_icp/io/trajectory.h).

#include <vector>

#include <Eigen/Geometry>

namespace weighted_icp {

/// @brief A camera-to-world pose at a time.
struct StampedPose {
  double timestamp = 0.0;                                  // seconds
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  // camera to world
};

/// @brief Poses in the order they were produced (not necessarily by time).
using Trajectory = std::vector<StampedPose>;

}  // namespace weighted_icp
