#pragma once
// A copy of a front-end map's keyframes and landmarks, taken in blocks that
// never hold tracking up for long (frontend::Map::copyInBlocks) and never mix
// corrected with uncorrected poses, that place recognition and loop
// verification read without locking: which keyframes share landmarks, and the landmarks around a keyframe.

#include <cstddef>
#include <map>
#include <set>
#include <vector>

#include "weighted_icp/frontend/slam/keyframe.h"
#include "weighted_icp/frontend/slam/map.h"
#include "weighted_icp/frontend/slam/map_point.h"
#include "weighted_icp/registration/landmark_map.h"

namespace weighted_icp::mapping {

/// @brief Keyframes and map points by id, as a frontend::Map held them when copied.
struct KeyframeSnapshot {
  /// @brief Keyframes by id (poses camera-to-world, features kept).
  std::map<frontend::KeyframeId, frontend::Keyframe> keyframes;
  /// @brief Map points by id (world positions, covariances, descriptors, observations).
  std::map<frontend::MapPointId, frontend::MapPoint> points;

  /// @brief Copies a front-end map (keyframes first, then points, as frontend::toLandmarkMap does), in blocks
  /// (frontend::Map::copyInBlocks).
  /// @param map the map; not modified
  static KeyframeSnapshot of(const frontend::Map& map);

  /// @brief The keyframes that observe at least one landmark `keyframe` observes (itself excluded):
  /// the ones place recognition must not propose, since tracking already links them.
  /// @param keyframe a keyframe id; an unknown one gives an empty set
  std::set<frontend::KeyframeId> covisible(frontend::KeyframeId keyframe) const;

  /// @brief The keyframes of `keyframe`'s neighbourhood: those of its segment whose ids differ from it by at
  /// most `radius` (itself included), in id order. Its mini-map, as the tracker built it.
  /// @param keyframe a keyframe id; an unknown one gives an empty list
  /// @param radius how many keyframes before and after
  std::vector<frontend::KeyframeId> neighbourhood(frontend::KeyframeId keyframe, std::size_t radius) const;

  /// @brief The distance travelled between two keyframes: the sum of the translations between consecutive
  /// keyframes (in id order) from one to the other.
  /// @param a a keyframe id; unknown throws std::invalid_argument
  /// @param b a keyframe id; unknown throws std::invalid_argument
  double pathLength(frontend::KeyframeId a, frontend::KeyframeId b) const;

  /// @brief The landmark model of the points seen from `frames`: those frames' poses, and each point any of them
  /// observes with only their observations (as LandmarkMap::miniMap), in point-id order; landmark ids are
  /// map point ids.
  /// @param frames keyframe ids (unknown ones are skipped)
  LandmarkMap localLandmarks(const std::vector<frontend::KeyframeId>& frames) const;
};

}  // namespace weighted_icp::mapping
