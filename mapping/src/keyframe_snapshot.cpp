// The keyframe snapshot (see keyframe_snapshot.h): covisibility and local
// landmark sets computed from one consistent copy of the map.

#include "weighted_icp/mapping/keyframe_snapshot.h"

#include <algorithm>
#include <iterator>
#include <stdexcept>
#include <string>

namespace weighted_icp::mapping {

KeyframeSnapshot KeyframeSnapshot::of(const frontend::Map& map) {
  // In blocks: the loop closer takes a snapshot at every keyframe, and a whole copy under one lock made tracking
  // wait up to 32 ms for it (Map::copyInBlocks).
  frontend::MapCopy copy = map.copyInBlocks();
  KeyframeSnapshot snapshot;
  // Sorted by id: each goes at the end.
  for (frontend::Keyframe& keyframe : copy.keyframes)
    snapshot.keyframes.emplace_hint(snapshot.keyframes.end(), keyframe.id, std::move(keyframe));
  for (frontend::MapPoint& point : copy.points)
    snapshot.points.emplace_hint(snapshot.points.end(), point.id, std::move(point));
  return snapshot;
}

std::set<frontend::KeyframeId> KeyframeSnapshot::covisible(frontend::KeyframeId keyframe) const {
  std::set<frontend::KeyframeId> result;
  const auto found = keyframes.find(keyframe);
  if (found == keyframes.end()) return result;
  for (frontend::MapPointId id : found->second.observed_points) {
    const auto point = points.find(id);
    if (point == points.end()) continue;
    for (const frontend::MapPointObservation& o : point->second.observations)
      if (o.keyframe != keyframe) result.insert(o.keyframe);
  }
  return result;
}

double KeyframeSnapshot::pathLength(frontend::KeyframeId a, frontend::KeyframeId b) const {
  const auto first = keyframes.find(std::min(a, b));
  const auto last = keyframes.find(std::max(a, b));
  if (first == keyframes.end() || last == keyframes.end())
    throw std::invalid_argument("KeyframeSnapshot::pathLength: unknown keyframe " +
                                std::to_string(first == keyframes.end() ? std::min(a, b) : std::max(a, b)));
  double path = 0.0;
  for (auto it = first; it != last; ++it)
    path += (std::next(it)->second.pose_wc.translation() - it->second.pose_wc.translation()).norm();
  return path;
}

std::vector<frontend::KeyframeId> KeyframeSnapshot::neighbourhood(frontend::KeyframeId keyframe,
                                                                  std::size_t radius) const {
  std::vector<frontend::KeyframeId> result;
  const auto found = keyframes.find(keyframe);
  if (found == keyframes.end()) return result;
  const std::size_t segment = found->second.segment;
  const frontend::KeyframeId first = keyframe >= radius ? keyframe - radius : 0;
  for (auto it = keyframes.lower_bound(first); it != keyframes.end() && it->first <= keyframe + radius; ++it)
    if (it->second.segment == segment) result.push_back(it->first);
  return result;
}

LandmarkMap KeyframeSnapshot::localLandmarks(const std::vector<frontend::KeyframeId>& frames) const {
  LandmarkMap local;
  std::set<frontend::MapPointId> ids;
  for (frontend::KeyframeId id : frames) {
    const auto keyframe = keyframes.find(id);
    if (keyframe == keyframes.end()) continue;
    local.frames.emplace(id, keyframe->second.pose_wc);
    ids.insert(keyframe->second.observed_points.begin(), keyframe->second.observed_points.end());
  }
  for (frontend::MapPointId id : ids) {
    const auto point = points.find(id);
    if (point == points.end()) continue;
    Landmark landmark;
    landmark.id = id;
    landmark.position = point->second.position;
    landmark.covariance = point->second.covariance;
    for (const frontend::MapPointObservation& o : point->second.observations)
      if (local.frames.count(o.keyframe)) landmark.observations.push_back({o.keyframe, o.pixel.x(), o.pixel.y()});
    if (!landmark.observations.empty()) local.landmarks.push_back(std::move(landmark));
  }
  return local;
}

}  // namespace weighted_icp::mapping
