#pragma once
// The whole RGB-D SLAM: Map, Frontend and Backend wired together, with the
// per-frame record the tools report from.

#include <cstddef>
#include <memory>
#include <vector>

#include "weighted_icp/core/camera.h"
#include "weighted_icp/core/trajectory.h"
#include "weighted_icp/frontend/slam/backend.h"
#include "weighted_icp/frontend/slam/frontend.h"
#include "weighted_icp/frontend/slam/map.h"
#include "weighted_icp/frontend/slam/minimap_builder.h"
#include "weighted_icp/registration/landmark_map.h"

namespace weighted_icp::frontend {

struct RgbdSlamOptions {
  FrontendOptions frontend;
  BackendOptions backend;
  std::size_t minimap_keyframes = 10;
};

struct FrameRecord {
  double timestamp = 0.0;
  TrackingResult result;
  double tracking_ms = 0.0;  // time spent in Frontend::track
  /// CPU time of the tracking thread in Frontend::track (issue #11): unlike the wall time it does not grow
  /// when other processes load the machine, so speed changes can be compared on a busy machine.
  double tracking_cpu_ms = 0.0;
};

class RgbdSlam {
 public:
  RgbdSlam(const PinholeCamera& camera, const RgbdSlamOptions& options = {});

  const FrameRecord& process(const RgbdFrame& image);
  /// Waits for the backend to finish its pending optimisation.
  void finish();

  const std::vector<FrameRecord>& frames() const { return frames_; }
  const Map& map() const { return map_; }
  /// The map, for the mapping layer's loop closing, which posts pose-graph corrections to it.
  Map& map() { return map_; }
  /// Applies a pose-graph correction still pending after the last frame (the
  /// next frame would have); returns true if there was one.
  bool applyPendingCorrection() { return frontend_.followMapCorrection(); }
  std::size_t optimizationsRun() const { return backend_.optimizationsRun(); }
  /// @brief A global bundle adjustment: every keyframe of the current segment and the points they observe at once
  /// (the oldest keyframe fixed), with the backend's noise model and solver, after finish(). Frames follow their
  /// reference keyframes, so the trajectory moves with it.
  /// @param max_iterations Levenberg-Marquardt iterations (the local windows use the backend's setting)
  /// @return true when a solution was written back
  bool bundleAdjustWholeSegment(int max_iterations);
  /// One pose per frame that got one (camera-to-world), expressed through its
  /// reference keyframe as the backend left it.
  Trajectory trajectory() const;
  /// The whole map in registration's model (toLandmarkMap).
  LandmarkMap sessionMap() const;
  std::vector<LandmarkMap> miniMaps() const { return minimap_builder_.build(map_); }

 private:
  Map map_;  // first: the backend and frontend hold references to it
  PinholeCamera camera_;
  BackendOptions backend_options_;
  Backend backend_;
  Frontend frontend_;
  MiniMapBuilder minimap_builder_;
  std::vector<FrameRecord> frames_;
};

}  // namespace weighted_icp::frontend
