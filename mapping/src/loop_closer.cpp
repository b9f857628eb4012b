// The loop-closing stage: detection per keyframe, pose-graph optimisation per loop, corrections posted to the map.
#include "weighted_icp/mapping/loop_closer.h"

#include <stdexcept>
#include <string>
#include <utility>

#include "weighted_icp/core/background_thread.h"
#include "weighted_icp/mapping/keyframe_snapshot.h"

namespace weighted_icp::mapping {

namespace {

/// Per odometry edge (entry i: keyframes i-1 -> i; entry 0 empty), the relative pose's covariance from tracking,
/// when the landmarks hold it.
std::vector<std::optional<Covariance6d>> trackingCovariances(const frontend::Map& map,
                                                             const frontend::KeyframePoses& keyframes,
                                                             const PinholeCamera& camera,
                                                             const TrackingInformationOptions& options) {
  return odometryEdgeCovariances(KeyframeSnapshot::of(map), keyframes.ids, camera, options);
}

/// Nodes at the keyframe poses (the first fixed), odometry edges between consecutive keyframes: information from
/// tracking where the edge has a covariance (and no tracking loss lies between), else the noise model.
/// The edges' relative poses are the odometry's (corrections undone), not the corrected map's: the map as earlier
/// corrections left it is bent by their loop edges' errors, and edges read from it would freeze those errors in.
PoseGraph odometryGraph(const frontend::KeyframePoses& keyframes, const LoopClosingOptions& options,
                        const std::vector<std::optional<Covariance6d>>& covariances) {
  PoseGraph graph;
  for (std::size_t i = 0; i < keyframes.ids.size(); ++i) graph.addNode(keyframes.ids[i], keyframes.poses_wc[i], i == 0);
  const std::vector<Eigen::Isometry3d>& measured =
      keyframes.odometry_wc.size() == keyframes.ids.size() ? keyframes.odometry_wc : keyframes.poses_wc;
  for (std::size_t i = 1; i < keyframes.ids.size(); ++i) {
    const Eigen::Isometry3d relative = measured[i - 1].inverse() * measured[i];
    const bool across_segments = keyframes.segments[i - 1] != keyframes.segments[i];
    const bool tracked = !across_segments && i < covariances.size() && covariances[i];
    const Information6d information = tracked ? relativeOdometryInformation(*covariances[i], options.tracking)
                                              : odometryInformation(relative, options.odometry, across_segments);
    graph.addEdge({keyframes.ids[i - 1], keyframes.ids[i], relative, information, PoseGraphEdgeKind::Odometry});
  }
  return graph;
}

}  // namespace

LoopCloser::LoopCloser(frontend::Map& map, LoopDetector detector, LoopClosingOptions options)
    : map_(map), detector_(std::move(detector)), options_(std::move(options)) {
  if (!detector_) throw std::invalid_argument("LoopCloser: no loop detector given");
  if (options_.background_niceness < 0 || options_.background_niceness > 19)
    throw std::invalid_argument("LoopCloser: background_niceness must be between 0 and 19, got " +
                                std::to_string(options_.background_niceness));
  if (options_.background_thread) thread_ = std::thread([this] { run(); });
}

LoopCloser::~LoopCloser() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void LoopCloser::rethrowError() const {
  if (error_) std::rethrow_exception(error_);
}

void LoopCloser::keyframeInserted(frontend::KeyframeId keyframe) {
  if (!options_.background_thread) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      rethrowError();
    }
    try {
      process(keyframe);
    } catch (...) {
      std::lock_guard<std::mutex> lock(mutex_);
      error_ = std::current_exception();
      throw;
    }
    return;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    rethrowError();
    queue_.push_back(keyframe);
  }
  wake_.notify_one();
}

void LoopCloser::flush() {
  std::unique_lock<std::mutex> lock(mutex_);
  idle_.wait(lock, [this] { return (queue_.empty() && !running_) || error_; });
  rethrowError();
}

LoopClosingStats LoopCloser::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

std::vector<LoopConstraint> LoopCloser::acceptedLoops() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return loops_;
}

void LoopCloser::run() {
  nameThisThread("wicp-loops");
  // Refused only by a system that forbids it: loop closing then competes with tracking, as it did before.
  (void)lowerThisThreadPriority(options_.background_niceness);
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    wake_.wait(lock, [this] { return !queue_.empty() || stopping_; });
    // Queued keyframes are processed before stopping; after an error nothing more is.
    if (error_ || queue_.empty()) {
      if (stopping_) break;
      queue_.clear();
      continue;
    }
    const frontend::KeyframeId keyframe = queue_.front();
    queue_.pop_front();
    running_ = true;
    lock.unlock();
    std::exception_ptr error;
    try {
      process(keyframe);
    } catch (...) {
      error = std::current_exception();
    }
    lock.lock();
    running_ = false;
    if (error && !error_) error_ = error;
    idle_.notify_all();
  }
  idle_.notify_all();
}

void LoopCloser::process(frontend::KeyframeId keyframe) {
  const std::optional<LoopConstraint> loop = detector_(map_, keyframe);
  if (!loop) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++stats_.loops_detected;
  }
  if (!closeLoop(*loop)) return;
  std::lock_guard<std::mutex> lock(mutex_);
  ++stats_.loops_accepted;
  loops_.push_back(*loop);
}

bool LoopCloser::closeLoop(const LoopConstraint& candidate) {
  for (int attempt = 0; attempt <= options_.max_stale_retries; ++attempt) {
    const frontend::KeyframePoses keyframes = map_.keyframePoses();
    const std::vector<std::optional<Covariance6d>> covariances =
        options_.tracking_camera ? trackingCovariances(map_, keyframes, *options_.tracking_camera, options_.tracking)
                                 : std::vector<std::optional<Covariance6d>>{};
    PoseGraph graph = odometryGraph(keyframes, options_, covariances);
    const auto known = [&graph](const LoopConstraint& loop) {
      return graph.poses().count(loop.query) && graph.poses().count(loop.match);
    };
    // loops_ changes only in this thread: reading it here needs no lock.
    for (const LoopConstraint& loop : loops_)
      if (known(loop)) {
        PoseGraphEdge edge = loopEdge(loop);
        edge.admitted_before = true;  // accepted at an earlier closure: re-tested together, not one by one
        graph.addEdge(edge);
      }
    if (!known(candidate)) return false;  // names a keyframe the map does not have
    graph.addEdge(loopEdge(candidate));

    const PoseGraphSummary summary = graph.optimize(options_.pose_graph);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      ++stats_.pose_graph_optimisations;
    }
    if (!summary.ok) throw std::runtime_error("LoopCloser: pose-graph optimisation failed: " + summary.message);
    if (!summary.edge_used.back()) return false;

    frontend::PoseGraphCorrection correction;
    correction.base_corrections = keyframes.corrections;
    for (std::size_t i = 0; i < keyframes.ids.size(); ++i)
      correction.delta_wc[keyframes.ids[i]] = graph.poses().at(keyframes.ids[i]) * keyframes.poses_wc[i].inverse();
    if (map_.postCorrection(std::move(correction))) return true;
    // A correction was applied while this one was computed: read the poses again.
  }
  throw std::runtime_error("LoopCloser: the map kept changing under the pose-graph optimisation (" +
                           std::to_string(options_.max_stale_retries + 1) + " attempts)");
}

}  // namespace weighted_icp::mapping
