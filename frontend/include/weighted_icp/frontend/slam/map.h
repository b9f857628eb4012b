#pragma once
// The SLAM map shared by the tracking thread and the backend thread: keyframes
// and map points. Every call locks and hands out copies, so neither thread
// ever sees a half-updated landmark.

#include <cstddef>
#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <vector>

#include "weighted_icp/frontend/slam/keyframe.h"
#include "weighted_icp/frontend/slam/map_point.h"

namespace weighted_icp::frontend {

/// What the tracker matches against: the points seen by the latest keyframes.
struct LocalMap {
  std::uint64_t revision = 0;  // of the Map it was taken from
  std::vector<MapPointId> ids;
  std::vector<Eigen::Vector3d> positions;
  cv::Mat descriptors;  // row i belongs to ids[i]
};

/// A consistent copy of the latest keyframes and the points they observe,
/// for the backend to optimise without holding the lock.
struct MapWindow {
  std::vector<Keyframe> keyframes;  // oldest first
  std::vector<MapPoint> points;
};

class Map {
 public:
  /// Assigns and returns the keyframe id (0, 1, 2, ...).
  KeyframeId addKeyframe(Keyframe keyframe);
  /// Assigns and returns the point id; its observations are registered with their keyframes.
  MapPointId addMapPoint(MapPoint point);
  /// Adds an observation and replaces the point's position, covariance and descriptor.
  void addObservation(MapPointId id, const MapPointObservation& observation, const Eigen::Vector3d& position,
                      const Eigen::Matrix3d& covariance, const cv::Mat& descriptor);

  /// Changes whenever anything in the map does: a tracker holding a LocalMap
  /// of the same revision need not take (or index) it again.
  std::uint64_t revision() const;
  std::optional<Eigen::Isometry3d> keyframePose(KeyframeId id) const;
  std::optional<MapPoint> mapPoint(MapPointId id) const;
  /// Points observed by the last `keyframes` keyframes of the current segment.
  LocalMap localMap(std::size_t keyframes) const;
  MapWindow window(std::size_t keyframes) const;

  /// Writes back what the backend optimised: keyframe poses and point
  /// positions/covariances, for the ids that still exist; removes the listed
  /// observations (outliers) and points left with none.
  void applyOptimization(const MapWindow& optimised,
                         const std::vector<std::pair<MapPointId, KeyframeId>>& rejected_observations);

  std::vector<Keyframe> keyframes() const;
  std::vector<MapPoint> mapPoints() const;
  std::size_t keyframeCount() const;
  std::size_t mapPointCount() const;

 private:
  std::vector<MapPointId> currentSegmentPoints(std::size_t keyframes) const;  // lock held

  mutable std::mutex mutex_;
  std::map<KeyframeId, Keyframe> keyframes_;
  std::map<MapPointId, MapPoint> points_;
  std::uint64_t revision_ = 0;
  KeyframeId next_keyframe_id_ = 0;
  MapPointId next_point_id_ = 0;
};

}  // namespace weighted_icp::frontend
