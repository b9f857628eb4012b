#pragma once
// Ground truth for place recognition: whether two keyframes see the same
// part of the scene, from their true poses and the first one's landmarks.

#include "weighted_icp/core/camera.h"
#include "weighted_icp/frontend/slam/map_point.h"
#include "weighted_icp/mapping/keyframe_snapshot.h"

namespace weighted_icp::mapping {

/// @brief The fraction of the landmarks keyframe `a` observes that keyframe `b`'s camera sees too: in front
/// of it, within its image and no farther than `max_depth`, judged from the snapshot's poses and positions
/// (so meaningful when those are true, e.g. from PosedKeyframeBuilder with ground-truth poses). A true
/// revisit is a pair with enough overlap; occlusion is not modelled.
/// @param snapshot the keyframes and landmarks
/// @param a the keyframe whose landmarks are counted; unknown or without landmarks gives 0
/// @param b the keyframe whose view is tested; unknown gives 0
/// @param camera the image both were taken with (undistorted)
/// @param max_depth metres
double viewOverlap(const KeyframeSnapshot& snapshot, frontend::KeyframeId a, frontend::KeyframeId b,
                   const PinholeCamera& camera, double max_depth = 5.0);

}  // namespace weighted_icp::mapping
