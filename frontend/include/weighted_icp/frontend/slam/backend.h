#pragma once
// The backend: local bundle adjustment over the latest keyframes, in its own
// thread while tracking goes on (or inline, deterministic, for tests).
//
// Hand-off: the tracker inserts a keyframe into the Map and calls
// keyframeInserted(); the backend copies the window out of the Map, optimises
// without holding the lock, and writes poses, positions, covariances back.
// Requests that arrive while an optimisation runs are merged into one.

#include <condition_variable>
#include <cstddef>
#include <mutex>
#include <thread>

#include "weighted_icp/core/camera.h"
#include "weighted_icp/frontend/geometry/local_bundle_adjustment.h"
#include "weighted_icp/frontend/slam/map.h"

namespace weighted_icp::frontend {

struct BackendOptions {
  std::size_t window_keyframes = 7;
  BundleAdjustmentOptions bundle_adjustment;
  /// false: optimise inside keyframeInserted(), so runs are reproducible.
  bool background_thread = true;
};

class Backend {
 public:
  Backend(Map& map, PinholeCamera camera, BackendOptions options = {});
  ~Backend();
  Backend(const Backend&) = delete;
  Backend& operator=(const Backend&) = delete;

  void keyframeInserted();
  /// Returns once nothing is pending or running.
  void flush();
  std::size_t optimizationsRun() const;

 private:
  void optimizeWindow();
  void run();

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
  std::thread thread_;
};

}  // namespace weighted_icp::frontend
