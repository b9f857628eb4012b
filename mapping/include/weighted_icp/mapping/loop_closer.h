#pragma once
// The loop-closing stage: for each new keyframe it asks a detector for a verified
// loop, and for one it optimises the pose graph of all keyframes and posts the
// correction to the map, which the tracker applies between two frames. Runs in
// its own thread (tracking never waits for it) or inline (deterministic, for tests).

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "weighted_icp/frontend/slam/map.h"
#include "weighted_icp/mapping/loop_constraint.h"
#include "weighted_icp/mapping/pose_graph.h"
#include "weighted_icp/mapping/tracking_information.h"

namespace weighted_icp::mapping {

/// @brief Place recognition + geometric verification as the loop closer sees it: given the map and a new keyframe,
/// a verified loop (query = that keyframe) or nothing. Called from the loop-closing thread only, one keyframe at a
/// time, in insertion order; it reads the map through its locking accessors.
using LoopDetector = std::function<std::optional<LoopConstraint>(const frontend::Map& map, frontend::KeyframeId query)>;

/// @brief Options of LoopCloser.
struct LoopClosingOptions {
  /// @brief false: detection and optimisation run inside keyframeInserted(), so runs are reproducible.
  bool background_thread = true;
  /// @brief Added to the background thread's nice value (0-19; Linux): with the cores busy, tracking runs first and
  /// loop closing takes the time left (a loop is closed later, never lost; at a camera's frame rate tracking leaves
  /// time). 0: the same priority as tracking.
  int background_niceness = 19;
  /// @brief Information of the odometry edges (consecutive keyframes, poses as tracking and bundle adjustment left
  /// them).
  OdometryNoiseModel odometry;
  /// @brief When set, the odometry edges' information is estimated from tracking (tracking_information.h: each
  /// keyframe's reprojection Hessian against its landmarks, with the pixels measured by this camera); an edge whose
  /// keyframes are not held by enough landmarks, or that spans a tracking loss, keeps the noise model. Unset: the
  /// noise model for every edge. LoopClosingSlam sets it to its camera.
  std::optional<PinholeCamera> tracking_camera;
  /// @brief How the tracking estimate is made (with tracking_camera).
  TrackingInformationOptions tracking;
  /// @brief Solver and loop-consistency gate.
  PoseGraphOptions pose_graph;
  /// @brief Times the optimisation is run again when a correction was applied while it ran (its poses are stale).
  int max_stale_retries = 3;
};

/// @brief What loop closing did so far.
struct LoopClosingStats {
  /// @brief Loops the detector returned.
  std::size_t loops_detected = 0;
  /// @brief Loops the pose graph admitted (and whose correction was posted).
  std::size_t loops_accepted = 0;
  /// @brief Pose-graph optimisations run (each may solve several times, see PoseGraphSummary::solves).
  std::size_t pose_graph_optimisations = 0;
};

/// @brief Loop closing over a front end's map.
class LoopCloser {
 public:
  using Ptr = std::shared_ptr<LoopCloser>;

  /// @brief Starts the thread in background mode; throws std::invalid_argument without a detector.
  /// @param map The SLAM map; must outlive this object.
  /// @param detector Finds and verifies loops.
  /// @param options Thread mode, noise model, gate.
  LoopCloser(frontend::Map& map, LoopDetector detector, LoopClosingOptions options = {});
  /// @brief Finishes the queued keyframes, then stops the thread; never throws (flush() reports errors).
  ~LoopCloser();
  LoopCloser(const LoopCloser&) = delete;
  LoopCloser& operator=(const LoopCloser&) = delete;

  /// @brief Queues a new keyframe (inline mode: processes it now). Rethrows an error of the loop-closing thread.
  /// @param keyframe The keyframe the tracker just inserted.
  void keyframeInserted(frontend::KeyframeId keyframe);
  /// @brief Returns once every queued keyframe is processed; rethrows the first error the detector or the
  /// optimisation raised (after which the loop closer processes nothing more).
  void flush();
  /// @brief Counters so far.
  LoopClosingStats stats() const;
  /// @brief The loops the pose graph admitted, in order.
  std::vector<LoopConstraint> acceptedLoops() const;
  /// @brief "LoopCloser".
  static std::string getClassName() { return "LoopCloser"; }

 private:
  void process(frontend::KeyframeId keyframe);
  /// Optimises the graph of all keyframes with the admitted loops and `candidate`; posts the correction if
  /// the candidate is admitted. Returns whether it was.
  bool closeLoop(const LoopConstraint& candidate);
  void run();
  void rethrowError() const;  // mutex_ held

  frontend::Map& map_;
  LoopDetector detector_;
  LoopClosingOptions options_;
  std::vector<LoopConstraint> loops_;  // admitted; touched by the processing thread only, read under mutex_

  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::condition_variable idle_;
  std::deque<frontend::KeyframeId> queue_;
  bool running_ = false;
  bool stopping_ = false;
  std::exception_ptr error_;
  LoopClosingStats stats_;
  std::thread thread_;
};

}  // namespace weighted_icp::mapping
