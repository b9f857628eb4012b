#include "weighted_icp/frontend/slam/minimap_builder.h"

#include <stdexcept>

#include "weighted_icp/frontend/slam/landmark_conversion.h"

namespace weighted_icp::frontend {

MiniMapBuilder::MiniMapBuilder(std::size_t keyframes_per_minimap) : keyframes_per_minimap_(keyframes_per_minimap) {
  if (keyframes_per_minimap_ == 0) throw std::invalid_argument("a mini-map needs at least one keyframe");
}

LandmarkMap MiniMapBuilder::sessionMap(const Map& map) { return toLandmarkMap(map); }

std::vector<LandmarkMap> MiniMapBuilder::build(const Map& map) const {
  const LandmarkMap session = toLandmarkMap(map);
  const std::vector<Keyframe> keyframes = map.keyframes();
  std::vector<LandmarkMap> minimaps;
  std::size_t start = 0;
  for (std::size_t i = 1; i <= keyframes.size(); ++i) {
    const bool segment_ends = i == keyframes.size() || keyframes[i].segment != keyframes[start].segment;
    if (!segment_ends && i - start < keyframes_per_minimap_) continue;
    minimaps.push_back(session.miniMap(keyframes[start].id, keyframes[i - 1].id));
    start = i;
  }
  return minimaps;
}

}  // namespace weighted_icp::frontend
