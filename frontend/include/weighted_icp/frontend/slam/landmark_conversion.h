#pragma once
// The one conversion from the front end's SLAM map to registration's landmark
// model: what the mini-maps, the session map and the mapping layer build on.

#include "weighted_icp/frontend/slam/map.h"
#include "weighted_icp/registration/landmark_map.h"
#include "weighted_icp/registration/landmark_point.h"
#include "weighted_icp/registration/weight_strategies.h"

namespace weighted_icp::frontend {

/// @brief The whole map as a LandmarkMap.
///
/// - every Keyframe becomes a frame: its id (KeyframeId) is the FrameId, its pose_wc the frame's camera-to-world
///   pose; segment, frame_id and timestamp are not carried over;
/// - every MapPoint becomes a Landmark, in point-id order: id, position and covariance as they are (the
///   descriptor is not carried over);
/// - every MapPointObservation becomes an Observation, in the point's order: keyframe id as frame_id, the
///   undistorted pixel as (u, v); its depth is not carried over (the landmark model has none).
///
/// Keyframes are copied first, then points (each under the map's lock). Called between frames, as RgbdSlam
/// does, every observation names a frame of the result; a keyframe added by another thread in between
/// could be missing. The backend only moves poses and points and drops observations, which is harmless.
/// @param map The front end's map; not modified.
/// @return Frames ordered by keyframe id, landmarks ordered by point id.
LandmarkMap toLandmarkMap(const Map& map);

/// @brief One weighted PCL point per map point, in point-id order: registration's toLandmarkCloud of toLandmarkMap.
/// @param map The front end's map.
/// @param weight A weight strategy (weight_strategies.h) or any `double(const LandmarkMetrics&)`.
LandmarkCloud::Ptr toWeightedLandmarkCloud(const Map& map, const WeightFunction& weight);

}  // namespace weighted_icp::frontend
