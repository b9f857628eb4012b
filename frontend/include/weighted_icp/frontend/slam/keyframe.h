#pragma once
// A frame kept in the map: its pose is optimised by the backend and its
// features anchor the landmarks.

#include <cstddef>
#include <vector>

#include <Eigen/Geometry>

#include "weighted_icp/frontend/slam/map_point.h"

namespace weighted_icp::frontend {

struct Keyframe {
  KeyframeId id = 0;
  std::size_t frame_id = 0;
  double timestamp = 0.0;
  Eigen::Isometry3d pose_wc = Eigen::Isometry3d::Identity();
  /// The mini-map segment it belongs to; a new segment starts after tracking is lost.
  std::size_t segment = 0;
  std::vector<MapPointId> observed_points;
};

}  // namespace weighted_icp::frontend
