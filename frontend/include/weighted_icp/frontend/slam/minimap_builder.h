#pragma once
// From the SLAM map to the paper's landmark maps: the whole session, and the
// mini-maps the weighted ICP aligns (every N keyframes, never across a
// tracking loss).

#include <cstddef>
#include <vector>

#include "weighted_icp/frontend/slam/map.h"
#include "weighted_icp/registration/landmark_map.h"

namespace weighted_icp::frontend {

class MiniMapBuilder {
 public:
  /// Throws std::invalid_argument for 0.
  explicit MiniMapBuilder(std::size_t keyframes_per_minimap);

  /// Deprecated: call toLandmarkMap (landmark_conversion.h), which this forwards to.
  static LandmarkMap sessionMap(const Map& map);

  /// Consecutive mini-maps of up to N keyframes; a segment (tracking lost and
  /// restarted) always starts a new one. Each keeps only its keyframes'
  /// observations (LandmarkMap::miniMap of toLandmarkMap's session map).
  std::vector<LandmarkMap> build(const Map& map) const;

 private:
  std::size_t keyframes_per_minimap_;
};

}  // namespace weighted_icp::frontend
