// Viewing overlap of two keyframes (see view_overlap.h).

#include "weighted_icp/mapping/view_overlap.h"

namespace weighted_icp::mapping {

double viewOverlap(const KeyframeSnapshot& snapshot, frontend::KeyframeId a, frontend::KeyframeId b,
                   const PinholeCamera& camera, double max_depth) {
  const auto first = snapshot.keyframes.find(a);
  const auto second = snapshot.keyframes.find(b);
  if (first == snapshot.keyframes.end() || second == snapshot.keyframes.end()) return 0.0;
  const Eigen::Isometry3d world_to_b = second->second.pose_wc.inverse();
  std::size_t counted = 0, seen = 0;
  for (frontend::MapPointId id : first->second.observed_points) {
    const auto point = snapshot.points.find(id);
    if (point == snapshot.points.end()) continue;
    ++counted;
    const Eigen::Vector3d in_b = world_to_b * point->second.position;
    if (in_b.z() <= 0.0 || in_b.z() > max_depth) continue;
    if (camera.inImage(camera.project(in_b))) ++seen;
  }
  return counted ? static_cast<double>(seen) / static_cast<double>(counted) : 0.0;
}

}  // namespace weighted_icp::mapping
