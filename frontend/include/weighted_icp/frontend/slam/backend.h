#pragma once
// The backend: local bundle adjustment over the latest keyframes, in its own
// thread while tracking goes on (or inline, deterministic, for tests).
//
// Hand-off: the tracker inserts a keyframe into the Map and calls
// keyframeInserted(); the backend copies the window out of the Map, optimises
// without holding the lock, and writes poses, positions, covariances back.
// Requests that arrive while an optimisation runs are merged into one.
// An optimisation that throws stops the backend: the exception is kept and
// rethrown to the tracking thread by the next keyframeInserted() or flush(),
// so a failure is reported where it can be handled, never std::terminate.
// The solve itself is replaceable (BackendOptions::solver), as LoopCloser's
// detector is: that is how the tests make an optimisation throw.

#include <condition_variable>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>

#include "weighted_icp/core/camera.h"
#include "weighted_icp/frontend/geometry/local_bundle_adjustment.h"
#include "weighted_icp/frontend/slam/map.h"

namespace weighted_icp::frontend {

/// @brief The backend's optimisation step: solves one window's problem in place (poses not fixed, points) and says
/// how it went, as solveLocalBundleAdjustment does. Called from the backend's thread (inline mode: from
/// keyframeInserted()), one window at a time, without the map's lock; the backend writes the result back only
/// when the summary is ok. An exception it throws stops the backend and reaches tracking (see Backend).
using BundleAdjustmentSolver = std::function<BundleAdjustmentSummary(
    BundleAdjustmentProblem& problem, const PinholeCamera& camera, const BundleAdjustmentOptions& options)>;

/// @brief How the backend optimises: the window and bundle adjustment's options, in a thread or inline.
struct BackendOptions {
  std::size_t window_keyframes = 7;  ///< the latest keyframes optimised together
  BundleAdjustmentOptions bundle_adjustment;
  /// false: optimise inside keyframeInserted(), so runs are reproducible.
  bool background_thread = true;
  /// Replaces the solve (empty, the default: solveLocalBundleAdjustment with bundle_adjustment). For callers
  /// that wrap, observe or fail the optimisation, e.g. tests of error hand-off and shutdown.
  BundleAdjustmentSolver solver;
};

/// @brief One bundle adjustment of the latest `keyframes` keyframes of the map's current segment (the oldest of them
/// held fixed) and the points they observe, written back to the map: what the backend runs after each keyframe,
/// and, with `keyframes` at least the map's keyframe count, a global bundle adjustment of the whole segment.
/// @param map the map; written under its lock (Map::applyOptimization), skipped if a loop correction came between
/// @param camera the camera the observations were made with
/// @param options bundle-adjustment options and the solver (BackendOptions::solver, when set)
/// @param keyframes how many of the latest keyframes (fewer than 2: nothing is done)
/// @return true when a solution was written back
/// @throws std::runtime_error when a replaced solver reports success with a solution that does not fit the window
bool optimizeLatestKeyframes(Map& map, const PinholeCamera& camera, const BackendOptions& options,
                             std::size_t keyframes);

/// @brief Local bundle adjustment of the map's latest keyframes, in a background thread or inline.
class Backend {
 public:
  /// @brief Starts the thread when options.background_thread.
  /// @throws std::invalid_argument for a window under 2 keyframes or invalid bundle-adjustment
  /// options (with which nothing would ever be optimised)
  /// @param map     the map whose window is optimised; must outlive the backend
  /// @param camera  the camera the observations were made with
  /// @param options window and bundle-adjustment options
  Backend(Map& map, PinholeCamera camera, BackendOptions options = {});
  /// @brief Finishes the pending optimisation, then joins the thread (errors are dropped here).
  ~Backend();
  Backend(const Backend&) = delete;
  Backend& operator=(const Backend&) = delete;

  /// @brief Asks for an optimisation of the latest window (inline: runs it now).
  /// @throws whatever an earlier optimisation threw (the backend then stops optimising)
  void keyframeInserted();
  /// @brief Returns once nothing is pending or running.
  /// @throws whatever an optimisation threw
  void flush();
  /// @brief Optimisations finished so far.
  std::size_t optimizationsRun() const;

 private:
  void optimizeWindow();
  void run();
  void rethrowError() const;  // with mutex_ held

  Map& map_;
  PinholeCamera camera_;
  BackendOptions options_;

  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::condition_variable idle_;
  bool pending_ = false;
  bool running_ = false;
  bool stopping_ = false;
  std::size_t optimizations_ = 0;
  std::exception_ptr error_;  // the first exception an optimisation threw
  std::thread thread_;
};

}  // namespace weighted_icp::frontend
