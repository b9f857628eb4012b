// The backend: local bundle adjustment of the latest keyframes in its own thread, errors handed back to tracking.
#include "weighted_icp/frontend/slam/backend.h"

#include <stdexcept>
#include <string>
#include <unordered_map>

#include "weighted_icp/core/background_thread.h"

namespace weighted_icp::frontend {

namespace {
/// A replaced solver (BackendOptions::solver) is checked like any input: a successful solve must leave one pose per
/// keyframe and one point, covariance and outlier flag per point and observation of the window, or writing it back
/// would index past its vectors.
void requireSolutionFits(const BundleAdjustmentProblem& problem, const BundleAdjustmentSummary& summary,
                         const MapWindow& window, std::size_t observations) {
  const auto count = [](std::size_t actual, std::size_t expected, const char* what) {
    if (actual != expected)
      throw std::runtime_error(std::string("Backend: the solver reported success with ") + std::to_string(actual) +
                               " " + what + " for " + std::to_string(expected));
  };
  count(problem.poses_wc.size(), window.keyframes.size(), "poses");
  count(problem.points_world.size(), window.points.size(), "points");
  count(summary.point_covariances.size(), window.points.size(), "point covariances");
  count(summary.outlier_observations.size(), observations, "outlier flags");
}
}  // namespace

Backend::Backend(Map& map, PinholeCamera camera, BackendOptions options)
    : map_(map), camera_(camera), options_(options) {
  // Refused here, not skipped at every keyframe: with these the backend would never optimise anything.
  if (options_.window_keyframes < 2)
    throw std::invalid_argument("Backend: window_keyframes must be at least 2 (one pose is held fixed)");
  if (const auto problem = bundleAdjustmentOptionsProblem(options_.bundle_adjustment))
    throw std::invalid_argument("Backend: bundle_adjustment." + *problem);
  if (options_.background_thread) thread_ = std::thread([this] { run(); });
}

Backend::~Backend() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void Backend::rethrowError() const {
  if (error_) std::rethrow_exception(error_);
}

void Backend::keyframeInserted() {
  if (!options_.background_thread) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      rethrowError();
    }
    try {
      optimizeWindow();
    } catch (...) {
      std::lock_guard<std::mutex> lock(mutex_);
      error_ = std::current_exception();
      throw;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    ++optimizations_;
    return;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    rethrowError();
    pending_ = true;
  }
  wake_.notify_one();
}

void Backend::flush() {
  std::unique_lock<std::mutex> lock(mutex_);
  idle_.wait(lock, [this] { return (!pending_ && !running_) || error_; });
  rethrowError();
}

std::size_t Backend::optimizationsRun() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return optimizations_;
}

void Backend::run() {
  nameThisThread("wicp-ba");
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    wake_.wait(lock, [this] { return pending_ || stopping_; });
    // Pending work is finished before stopping: no keyframe is left unoptimised. After an error nothing more is
    // optimised (the map may be half-updated); the thread waits to be stopped.
    if ((!pending_ || error_) && stopping_) break;
    if (error_) {
      pending_ = false;
      continue;
    }
    pending_ = false;
    running_ = true;
    lock.unlock();
    std::exception_ptr error;
    try {
      optimizeWindow();
    } catch (...) {
      error = std::current_exception();
    }
    lock.lock();
    running_ = false;
    if (error)
      error_ = error;
    else
      ++optimizations_;
    idle_.notify_all();
  }
  idle_.notify_all();
}

void Backend::optimizeWindow() { optimizeLatestKeyframes(map_, camera_, options_, options_.window_keyframes); }

bool optimizeLatestKeyframes(Map& map, const PinholeCamera& camera, const BackendOptions& options,
                             std::size_t keyframes) {
  MapWindow window = map.window(keyframes);
  if (window.keyframes.size() < 2) return false;

  BundleAdjustmentProblem problem;
  std::unordered_map<KeyframeId, int> pose_index;
  for (const Keyframe& keyframe : window.keyframes) {
    pose_index.emplace(keyframe.id, static_cast<int>(problem.poses_wc.size()));
    problem.poses_wc.push_back(keyframe.pose_wc);
    problem.pose_fixed.push_back(problem.pose_fixed.empty());  // the oldest fixes the gauge
  }
  std::vector<std::pair<MapPointId, KeyframeId>> observation_ids;
  for (std::size_t j = 0; j < window.points.size(); ++j) {
    const MapPoint& point = window.points[j];
    problem.points_world.push_back(point.position);
    for (const auto& observation : point.observations) {
      const auto pose = pose_index.find(observation.keyframe);
      if (pose == pose_index.end()) continue;
      problem.observations.push_back({pose->second, static_cast<int>(j), observation.pixel, observation.depth});
      observation_ids.emplace_back(point.id, observation.keyframe);
    }
  }

  const BundleAdjustmentSummary summary = options.solver
                                              ? options.solver(problem, camera, options.bundle_adjustment)
                                              : solveLocalBundleAdjustment(problem, camera, options.bundle_adjustment);
  if (!summary.ok) return false;
  requireSolutionFits(problem, summary, window, observation_ids.size());
  for (std::size_t i = 0; i < window.keyframes.size(); ++i) window.keyframes[i].pose_wc = problem.poses_wc[i];
  for (std::size_t j = 0; j < window.points.size(); ++j) {
    window.points[j].position = problem.points_world[j];
    window.points[j].covariance = summary.point_covariances[j];
  }
  std::vector<std::pair<MapPointId, KeyframeId>> rejected;
  for (std::size_t k = 0; k < summary.outlier_observations.size(); ++k)
    if (summary.outlier_observations[k]) rejected.push_back(observation_ids[k]);
  map.applyOptimization(window, rejected);
  return true;
}

}  // namespace weighted_icp::frontend
