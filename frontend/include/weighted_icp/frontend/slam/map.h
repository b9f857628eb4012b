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
  /// Map::corrections() when it was taken: a window taken before a pose-graph
  /// correction is not written back (its poses are in the old frame).
  std::uint64_t corrections = 0;
};

/// The keyframe poses the pose graph starts from, read in one go.
struct KeyframePoses {
  std::uint64_t corrections = 0;  // Map::corrections() when they were read
  std::vector<KeyframeId> ids;    // ascending
  std::vector<Eigen::Isometry3d> poses_wc;
  std::vector<std::size_t> segments;
  /// The same poses with every pose-graph correction undone (C_k^-1 * pose_wc, C_k the corrections applied to
  /// keyframe k, or to the keyframe it was tracked from when it came later): what tracking and bundle adjustment
  /// measured. Relative poses of neighbours taken from these are odometry; taken from poses_wc they would carry
  /// the bends that earlier loop corrections put into the map, and a pose graph reading them would keep every
  /// earlier loop edge's error as if it were measured.
  std::vector<Eigen::Isometry3d> odometry_wc;
};

/// @brief A pose-graph correction: per keyframe, the world-frame motion that
/// takes its pose from where the pose graph read it to where the optimisation
/// put it (new = delta_wc * old).
///
/// Keyframes it does not list (added after the poses were read) move with the
/// nearest listed keyframe before them, which they were tracked from; every map
/// point moves with its reference keyframe, the first keyframe still observing
/// it, and its covariance turns with it.
struct PoseGraphCorrection {
  /// Map::corrections() when the corrected poses were read (KeyframePoses::corrections).
  std::uint64_t base_corrections = 0;
  std::map<KeyframeId, Eigen::Isometry3d> delta_wc;
};

/// @brief A copy of a map's keyframes and points (Map::copyInBlocks), each sorted by id.
struct MapCopy {
  std::vector<Keyframe> keyframes;
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
  /// observations (outliers) and points left with none. Does nothing when a
  /// pose-graph correction was applied since the window was taken.
  void applyOptimization(const MapWindow& optimised,
                         const std::vector<std::pair<MapPointId, KeyframeId>>& rejected_observations);

  /// @brief Every keyframe's pose and segment, with the correction count, under one lock.
  KeyframePoses keyframePoses() const;
  /// @brief How many pose-graph corrections have been applied.
  std::uint64_t corrections() const;
  /// @brief Hands a correction to the tracking thread, which applies it between
  /// two frames (applyPendingCorrection), so a frame is never tracked half in the
  /// old frame and half in the new. Replaces a correction still pending: the
  /// newer one was computed from the same poses with every loop so far.
  /// @param correction The correction.
  /// @return false (nothing posted) when it is stale: a correction was applied
  /// after its poses were read, so they must be read and optimised again.
  bool postCorrection(PoseGraphCorrection correction);
  /// @brief True while a posted correction waits to be applied.
  bool correctionPending() const;
  /// @brief Applies the pending correction, if any, to keyframes and points in
  /// one step (revision and corrections() bump).
  /// @param follow A keyframe whose correction the caller wants back.
  /// @return The world-frame correction applied to `follow` (identity if it is
  /// unknown), or nothing when no correction was pending.
  std::optional<Eigen::Isometry3d> applyPendingCorrection(KeyframeId follow);

  std::vector<Keyframe> keyframes() const;
  std::vector<MapPoint> mapPoints() const;
  /// @brief Every keyframe and map point, copied a few at a time for a background reader (loop closing): the lock
  /// is released between blocks, so that tracking waits at most one block's copy. A whole copy holds it for long:
  /// 14 ms in the median, 32 ms at worst, for the 60,000 points of a 1000-frame run, at every keyframe. A pose-graph
  /// correction applied while copying restarts the copy, so the result never mixes corrected and uncorrected poses;
  /// a keyframe or point added, optimised or removed meanwhile may be seen in its old or its new state (as between
  /// two calls of keyframes() and mapPoints()).
  /// @param keyframes_per_block keyframes copied under one lock (at least 1)
  /// @param points_per_block map points copied under one lock (at least 1)
  MapCopy copyInBlocks(std::size_t keyframes_per_block = 8, std::size_t points_per_block = 1024) const;
  std::size_t keyframeCount() const;
  std::size_t mapPointCount() const;

 private:
  std::vector<MapPointId> currentSegmentPoints(std::size_t keyframes) const;  // lock held
  /// Appends `source`'s values to `out`, `per_block` under each lock; false when a correction other than the
  /// `corrections`-th was applied meanwhile.
  template <typename Id, typename Value>
  bool copyBlocks(const std::map<Id, Value>& source, std::size_t per_block, std::uint64_t corrections,
                  std::vector<Value>& out) const;
  /// The correction of a keyframe: its own, else that of the nearest listed keyframe before it.
  static Eigen::Isometry3d deltaOf(const PoseGraphCorrection& correction, KeyframeId id);

  mutable std::mutex mutex_;
  std::map<KeyframeId, Keyframe> keyframes_;
  std::map<MapPointId, MapPoint> points_;
  std::uint64_t revision_ = 0;
  std::uint64_t corrections_ = 0;
  std::optional<PoseGraphCorrection> pending_correction_;
  /// Per keyframe, the world-frame motion all applied corrections gave it (KeyframePoses::odometry_wc).
  std::map<KeyframeId, Eigen::Isometry3d> corrected_by_;
  KeyframeId next_keyframe_id_ = 0;
  MapPointId next_point_id_ = 0;
};

}  // namespace weighted_icp::frontend
