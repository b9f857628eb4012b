#pragma once
// Whether two maps put in one frame contradict each other: a landmark of one lying in space a keyframe of the
// other saw through. What rejects a merge of sessions that look alike (perceptual aliasing, e.g. the same
// texture on different walls) when the agreeing loops cannot: every aliased loop agrees on the same wrong
// transform, but the rest of the two maps then floats in each other's empty space.

#include <cstddef>

#include <Eigen/Geometry>

#include "weighted_icp/core/camera.h"
#include "weighted_icp/mapping/keyframe_snapshot.h"

namespace weighted_icp::mapping {

/// @brief Options of checkFreeSpace.
struct FreeSpaceOptions {
  /// @brief Side of the square image cells, pixels, whose features' depths stand for the surface seen there.
  int cell_px = 16;
  /// @brief A landmark is in front of a surface when nearer than its nearest feature by more than
  /// `margin_m + margin_per_depth * depth`: the merge's own tolerance (its loops agree within 10 cm) plus the
  /// depth noise of a Kinect-like sensor and of the landmark, which grow with depth.
  double margin_m = 0.10, margin_per_depth = 0.05;
  /// @brief Landmarks nearer or farther than this from a keyframe are not judged (no depth is measured there).
  double min_depth_m = 0.3, max_depth_m = 4.5;
};

/// @brief What the check counted.
struct FreeSpaceCheck {
  /// @brief Landmark sightings (a landmark in one keyframe) consistent with what the keyframe measured in that
  /// direction (at its surface), and in front of every surface it measured there (in its free space).
  std::size_t supported_sightings = 0, violating_sightings = 0;
  /// @brief Landmarks judged in at least one keyframe, and those judged in free space more often than at a surface.
  std::size_t landmarks_judged = 0, landmarks_violating = 0;
  /// @brief landmarks_violating / landmarks_judged; 0 when nothing could be judged. A landmark decides by the
  /// majority of its sightings: a correct merge keeps a few sightings in free space (a landmark with a wrong depth,
  /// an occluder the features missed), rarely a majority; a wrong one puts whole surfaces there.
  double violationRatio() const {
    return landmarks_judged == 0 ? 0.0
                                 : static_cast<double>(landmarks_violating) / static_cast<double>(landmarks_judged);
  }
  /// @brief Adds another check's counts (e.g. the other direction).
  FreeSpaceCheck& operator+=(const FreeSpaceCheck& other) {
    supported_sightings += other.supported_sightings;
    violating_sightings += other.violating_sightings;
    landmarks_judged += other.landmarks_judged;
    landmarks_violating += other.landmarks_violating;
    return *this;
  }
};

/// @brief Projects every landmark of `other`, moved by `other_in_observer`, into every keyframe of `observer` and
/// compares its depth with the depths the keyframe measured at its features in the same image cell: a landmark
/// nearer than the nearest of them (beyond the margin) lies in space the keyframe saw through, a violating
/// sighting; one between the nearest and the farthest (within the margin) is supported; farther ones (hidden) and
/// cells without a measured depth are not judged. Occlusion is judged only from the features' own depths. Each
/// landmark then counts as violating when more of its sightings violate than are supported.
/// @param observer the keyframes whose measured depths are the reference
/// @param observer_camera their camera (undistorted pixels)
/// @param other the map whose landmarks are checked
/// @param other_in_observer `other`'s world in `observer`'s world
/// @param options see FreeSpaceOptions
FreeSpaceCheck checkFreeSpace(const KeyframeSnapshot& observer, const PinholeCamera& observer_camera,
                              const KeyframeSnapshot& other, const Eigen::Isometry3d& other_in_observer,
                              const FreeSpaceOptions& options = {});

}  // namespace weighted_icp::mapping
