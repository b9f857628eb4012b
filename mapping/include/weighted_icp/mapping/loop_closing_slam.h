#pragma once
// RGB-D SLAM with loop closure: frontend::RgbdSlam (tracking, local bundle
// adjustment) and a LoopCloser over its map, composed here because the front
// end cannot depend on the mapping layer. What the tools use.

#include <memory>
#include <optional>
#include <string>

#include "weighted_icp/core/camera.h"
#include "weighted_icp/core/trajectory.h"
#include "weighted_icp/frontend/slam/rgbd_slam.h"
#include "weighted_icp/mapping/loop_closer.h"

namespace weighted_icp::mapping {

/// @brief Options of LoopClosingSlam.
struct LoopClosingSlamOptions {
  /// @brief Tracking, bundle adjustment, mini-maps.
  frontend::RgbdSlamOptions slam;
  /// @brief The loop-closing stage.
  LoopClosingOptions loop_closing;
  /// @brief false: no loop closing at all (the detector is never called), as `--no-loop-closure`.
  bool loop_closure = true;
  /// @brief true: the pose graph's odometry edges take their information from tracking (the camera is given to
  /// loop_closing.tracking_camera unless one is set there); false: the noise model for every edge.
  bool odometry_from_tracking = true;
  /// @brief Levenberg-Marquardt iterations of a global bundle adjustment run by finish(), after the last loop
  /// correction (every keyframe of the current segment and its points at once); 0: none.
  int global_bundle_adjustment_iterations = 0;
};

/// @brief frontend::RgbdSlam plus loop closing. Every keyframe goes to the loop closer; the corrections it posts
/// are applied by the tracker between frames, and the trajectory (each frame through its reference keyframe)
/// becomes the corrected one.
class LoopClosingSlam {
 public:
  /// @brief Throws std::invalid_argument when loop closure is on and `detector` is empty.
  /// @param camera The camera of the sequence.
  /// @param detector Finds and verifies loops (may be empty when options.loop_closure is false).
  /// @param options See LoopClosingSlamOptions.
  LoopClosingSlam(const PinholeCamera& camera, LoopDetector detector, const LoopClosingSlamOptions& options = {});

  /// @brief Tracks one frame (RgbdSlam::process) and hands a new keyframe to the loop closer.
  /// @param image The frame. Rethrows an error of the loop-closing thread.
  const frontend::FrameRecord& process(const RgbdFrame& image);
  /// @brief Waits for bundle adjustment and loop closing, then applies a correction still pending, then runs the
  /// global bundle adjustment when the options ask for one.
  void finish();
  /// @brief Whether finish() ran a global bundle adjustment that was written back.
  bool globalBundleAdjusted() const { return global_bundle_adjusted_; }

  /// @brief The SLAM inside (frames, map, mini-maps).
  const frontend::RgbdSlam& slam() const { return slam_; }
  /// @brief The corrected trajectory (RgbdSlam::trajectory).
  Trajectory trajectory() const { return slam_.trajectory(); }
  /// @brief Loop-closing counters (all zero when loop closure is off).
  LoopClosingStats loopStats() const;
  /// @brief The admitted loops, in order.
  std::vector<LoopConstraint> acceptedLoops() const;

 private:
  frontend::RgbdSlam slam_;
  std::unique_ptr<LoopCloser> loop_closer_;  // after slam_: built on its map, destroyed first
  int global_bundle_adjustment_iterations_ = 0;
  bool global_bundle_adjusted_ = false;
};

}  // namespace weighted_icp::mapping
