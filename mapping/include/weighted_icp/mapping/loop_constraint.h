#pragma once
// A verified loop: what place recognition and geometric verification hand to
// the pose graph. Shared by both sides of the mapping layer, so that neither
// depends on the other's internals.

#include <cstddef>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "weighted_icp/frontend/slam/map_point.h"

namespace weighted_icp::mapping {

/// @brief A relative-pose constraint between two keyframes that the tracker did not link:
/// a loop (same session) or a merge edge (two sessions).
struct LoopConstraint {
  /// @brief The newer keyframe, the one that asked "have I been here before?".
  frontend::KeyframeId query = 0;
  /// @brief The older keyframe the loop joins: the one it was recognised as or, for a PnP edge, that keyframe's
  /// neighbour that saw the most of the PnP inliers (LoopVerifier::verify).
  frontend::KeyframeId match = 0;
  /// @brief Pose of the query keyframe's camera in the match keyframe's camera frame
  /// (camera-to-camera: x_match = query_in_match * x_query).
  Eigen::Isometry3d query_in_match = Eigen::Isometry3d::Identity();
  /// @brief Information (inverse covariance) of query_in_match, ordered (translation x y z,
  /// rotation x y z as a small rotation vector applied on the right), as the pose graph uses it.
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Identity();
  /// @brief Descriptor matches that agreed with the pose (PnP inliers).
  std::size_t inliers = 0;
  /// @brief PCL fitness score (mean squared nearest-neighbour distance, m^2) of the landmark
  /// clouds after the weighted ICP check.
  double fitness = 0.0;
  /// @brief Place recognition score of the match (normalised bag-of-words similarity, 0..1).
  double score = 0.0;
};

}  // namespace weighted_icp::mapping
