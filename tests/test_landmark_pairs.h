#pragma once
// Pairs of landmark maps cut from one map with no landmark in both, as wicp_global_sweep --disjoint cuts them: the
// registration tests' partial overlaps and mini-maps inside their whole map.

#include <utility>

#include "weighted_icp/registration/landmark_map.h"

namespace weighted_icp::testing {

/// The landmarks `a` and `b` both hold dealt out (dealOutSharedLandmarks: `a` keeps the even ids), as wicp_global_sweep
/// --disjoint does; then at least 2 observations each.
inline std::pair<LandmarkMap, LandmarkMap> dealtOut(LandmarkMap a, LandmarkMap b) {
  dealOutSharedLandmarks(a, b);
  return {a.withMinObservations(2), b.withMinObservations(2)};
}

/// Mini-maps of frames [0, first_last] and [second_first, ...] of `map`, dealt out (dealtOut).
inline std::pair<LandmarkMap, LandmarkMap> disjointPair(const LandmarkMap& map, FrameId first_last,
                                                        FrameId second_first) {
  return dealtOut(map.miniMap(0, first_last), map.miniMap(second_first, map.frames.rbegin()->first));
}

/// The whole map and its mini-map of frames [first, last], dealt out (the mini-map keeps the even ids): {whole, mini}.
inline std::pair<LandmarkMap, LandmarkMap> mapAndMiniMap(const LandmarkMap& map, FrameId first, FrameId last) {
  auto [mini, whole] = dealtOut(map.miniMap(first, last), map);
  return {std::move(whole), std::move(mini)};
}

}  // namespace weighted_icp::testing
