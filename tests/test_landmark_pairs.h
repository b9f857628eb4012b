#pragma once
// Pairs of landmark maps cut from one map with no landmark in both, as wicp_global_sweep --disjoint cuts them: the
// registration tests' partial overlaps and mini-maps inside their whole map.

#include <set>
#include <utility>
#include <vector>

#include "weighted_icp/registration/landmark_map.h"

namespace weighted_icp::testing {

/// The landmarks `a` and `b` both hold dealt out by id parity (`a` keeps the even ones), as wicp_global_sweep
/// --disjoint does; then at least 2 observations each.
inline std::pair<LandmarkMap, LandmarkMap> dealtOut(LandmarkMap a, LandmarkMap b) {
  std::set<LandmarkId> in_a, in_b;
  for (const auto& l : a.landmarks) in_a.insert(l.id);
  for (const auto& l : b.landmarks) in_b.insert(l.id);
  const auto keep = [](LandmarkMap& m, const std::set<LandmarkId>& other, LandmarkId parity) {
    std::vector<Landmark> kept;
    for (const auto& l : m.landmarks)
      if (!other.count(l.id) || l.id % 2 == parity) kept.push_back(l);
    m.landmarks = kept;
  };
  keep(a, in_b, 0);
  keep(b, in_a, 1);
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
