// The Backend on its own, on a hand-made map of three keyframes with noisy
// observations of known points: inline and background threads agree, flush
// and the destructor leave no work behind, outliers leave the map, every
// request is counted, and an optimisation that throws (made to through
// BackendOptions::solver) reaches tracking and stops the thread cleanly.

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <future>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "test_geometry_scene.h"
#include "weighted_icp/frontend/slam/backend.h"
#include "weighted_icp/frontend/slam/map.h"

namespace {

using namespace weighted_icp;
using namespace weighted_icp::frontend;
using weighted_icp::testing::makePose;
using weighted_icp::testing::projectWorld;

struct Scene {
  PinholeCamera camera = weighted_icp::testing::syntheticCamera();
  std::vector<Eigen::Isometry3d> true_poses_wc;
  std::vector<Eigen::Vector3d> true_points;
  MapPointId outlier_point = 0;  // its observation from the last keyframe is 40 px off
};

Scene makeScene() {
  Scene scene;
  scene.true_poses_wc = {Eigen::Isometry3d::Identity(), makePose({0, 2, 0}, {0.10, 0.0, 0.0}),
                         makePose({1, 4, 0}, {0.20, 0.02, 0.0})};
  std::mt19937 rng(7);
  scene.true_points = weighted_icp::testing::pointsInView(scene.camera, scene.true_poses_wc[0], 80, 1.5, 3.0, rng);
  return scene;
}

/// The scene as a SLAM map would hold it mid-session: keyframes after the
/// first and every point off their true place, observations noisy. Seeded: two
/// calls give the same map.
void fillMap(Map& map, const Scene& scene) {
  std::mt19937 rng(11);
  for (std::size_t k = 0; k < scene.true_poses_wc.size(); ++k) {
    Keyframe keyframe;
    keyframe.pose_wc =
        k == 0 ? scene.true_poses_wc[k] : weighted_icp::testing::perturbPose(scene.true_poses_wc[k], 0.02, 1.0, rng);
    map.addKeyframe(keyframe);
  }
  std::normal_distribution<double> offset(0.0, 0.02);
  for (std::size_t j = 0; j < scene.true_points.size(); ++j) {
    MapPoint point;
    point.position = scene.true_points[j] + Eigen::Vector3d(offset(rng), offset(rng), offset(rng));
    point.descriptor = cv::Mat(1, 32, CV_8U, cv::Scalar::all(0));
    for (std::size_t k = 0; k < scene.true_poses_wc.size(); ++k) {
      const Eigen::Vector3d in_camera = scene.true_poses_wc[k].inverse() * scene.true_points[j];
      Eigen::Vector2d pixel = projectWorld(scene.camera, scene.true_poses_wc[k], scene.true_points[j]) +
                              weighted_icp::testing::gaussianPixel(0.5, rng);
      if (j == scene.outlier_point && k + 1 == scene.true_poses_wc.size()) pixel.x() += 40.0;
      point.observations.push_back({k, pixel, in_camera.z()});
    }
    map.addMapPoint(std::move(point));
  }
}

BackendOptions inlineOptions() {
  BackendOptions options;
  options.background_thread = false;
  return options;
}

double worstPoseError(const Map& map, const Scene& scene) {
  double worst = 0.0;
  for (const Keyframe& keyframe : map.keyframes())
    worst = std::max(worst, (keyframe.pose_wc.translation() - scene.true_poses_wc[keyframe.id].translation()).norm());
  return worst;
}

TEST(Backend, InlineOptimisationMovesTheWindowTowardsTheTruthAndDropsTheOutlier) {
  const Scene scene = makeScene();
  Map map;
  fillMap(map, scene);
  const double error_before = worstPoseError(map, scene);
  Backend backend(map, scene.camera, inlineOptions());
  backend.keyframeInserted();
  EXPECT_EQ(backend.optimizationsRun(), 1u);
  EXPECT_LT(worstPoseError(map, scene), 0.2 * error_before);
  EXPECT_EQ(map.keyframePose(0)->matrix(), scene.true_poses_wc[0].matrix());  // the oldest fixes the gauge
  const MapPoint outlier = *map.mapPoint(scene.outlier_point);
  EXPECT_EQ(outlier.observations.size(), scene.true_poses_wc.size() - 1);
  for (const auto& observation : outlier.observations) EXPECT_NE(observation.keyframe, 2u);
  // Covariances now come from the bundle adjustment, no longer the identity the points were made with.
  EXPECT_LT(map.mapPoint(1)->covariance.norm(), 0.1);
}

TEST(Backend, BackgroundThreadGivesTheInlineMapOnceFlushed) {
  const Scene scene = makeScene();
  Map inline_map, background_map;
  fillMap(inline_map, scene);
  fillMap(background_map, scene);
  Backend inline_backend(inline_map, scene.camera, inlineOptions());
  Backend background_backend(background_map, scene.camera);
  inline_backend.keyframeInserted();
  background_backend.keyframeInserted();
  background_backend.flush();
  EXPECT_EQ(background_backend.optimizationsRun(), 1u);

  const auto inline_keyframes = inline_map.keyframes(), background_keyframes = background_map.keyframes();
  ASSERT_EQ(background_keyframes.size(), inline_keyframes.size());
  for (std::size_t k = 0; k < inline_keyframes.size(); ++k)
    EXPECT_EQ(background_keyframes[k].pose_wc.matrix(), inline_keyframes[k].pose_wc.matrix()) << "keyframe " << k;
  const auto inline_points = inline_map.mapPoints(), background_points = background_map.mapPoints();
  ASSERT_EQ(background_points.size(), inline_points.size());
  for (std::size_t j = 0; j < inline_points.size(); ++j) {
    EXPECT_EQ(background_points[j].position, inline_points[j].position) << "point " << j;
    EXPECT_EQ(background_points[j].covariance, inline_points[j].covariance) << "point " << j;
    EXPECT_EQ(background_points[j].observations.size(), inline_points[j].observations.size()) << "point " << j;
  }
}

TEST(Backend, FlushReturnsWithNothingPendingOrRunning) {
  const Scene scene = makeScene();
  Map map;
  fillMap(map, scene);
  Backend backend(map, scene.camera);
  backend.flush();  // nothing asked yet: returns at once
  EXPECT_EQ(backend.optimizationsRun(), 0u);
  for (int i = 0; i < 3; ++i) backend.keyframeInserted();
  backend.flush();
  // Requests arriving while one runs are merged, never lost: at least one, at most one each.
  const std::size_t runs = backend.optimizationsRun();
  EXPECT_GE(runs, 1u);
  EXPECT_LE(runs, 3u);
  const std::uint64_t revision = map.revision();
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_EQ(map.revision(), revision);  // nothing was still on its way
  EXPECT_EQ(backend.optimizationsRun(), runs);
}

TEST(Backend, DestructorFinishesPendingWorkBeforeJoining) {
  const Scene scene = makeScene();
  Map map;
  fillMap(map, scene);
  const std::uint64_t revision = map.revision();
  const double error_before = worstPoseError(map, scene);
  {
    Backend backend(map, scene.camera);
    backend.keyframeInserted();
  }  // joins here, with the request possibly not even started
  EXPECT_GT(map.revision(), revision);
  EXPECT_LT(worstPoseError(map, scene), error_before);
}

TEST(Backend, ASingleKeyframeIsCountedButLeftAlone) {
  const Scene scene = makeScene();
  Map map;
  Keyframe keyframe;
  map.addKeyframe(keyframe);
  map.addMapPoint([] {
    MapPoint point;
    point.position = Eigen::Vector3d(0.0, 0.0, 2.0);
    point.observations.push_back({0, Eigen::Vector2d(320.0, 240.0), 2.0});
    return point;
  }());
  const std::uint64_t revision = map.revision();
  Backend backend(map, scene.camera, inlineOptions());
  backend.keyframeInserted();
  backend.keyframeInserted();
  EXPECT_EQ(backend.optimizationsRun(), 2u);  // each inline request counts
  EXPECT_EQ(map.revision(), revision);        // one pose is all gauge: nothing to optimise
}

}  // namespace

// Options with which nothing could ever be optimised are refused when the backend is made, not skipped silently at
// every keyframe (the bundle adjustment used to report them only in a summary the backend did not read).
TEST(Backend, OptionsThatCouldNeverOptimiseAreRefused) {
  const Scene scene = makeScene();
  Map map;
  BackendOptions window_of_one = inlineOptions();
  window_of_one.window_keyframes = 1;
  EXPECT_THROW(Backend(map, scene.camera, window_of_one), std::invalid_argument);
  BackendOptions no_threads;
  no_threads.bundle_adjustment.threads = 0;
  try {
    Backend backend(map, scene.camera, no_threads);
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("bundle_adjustment.threads must be at least 1"), std::string::npos)
        << e.what();
  }
}

namespace {

const std::string kInjectedError = "injected: the solver ran out of memory";

/// Calls `call` in its own thread and aborts the test program, naming the call, if it has not returned after two
/// minutes: a deadlock would otherwise hang the suite until ctest's timeout without saying where. Not a speed check:
/// the calls take milliseconds, the bound leaves room for sanitizer builds. Rethrows what `call` threw.
template <typename Call>
void returnsWithoutDeadlock(const char* what, Call call) {
  std::future<void> done = std::async(std::launch::async, call);
  if (done.wait_for(std::chrono::minutes(2)) == std::future_status::timeout) {
    std::fprintf(stderr, "%s did not return within two minutes: deadlock\n", what);
    std::abort();
  }
  done.get();
}

/// What `call` threw as std::runtime_error, or "" when it returned.
template <typename Call>
std::string errorOf(const char* what, Call call) {
  try {
    returnsWithoutDeadlock(what, call);
  } catch (const std::runtime_error& error) {
    return error.what();
  }
  return "";
}

/// A solver that runs the real bundle adjustment `good_calls` times and then throws kInjectedError; counts its calls.
BundleAdjustmentSolver failingAfter(int good_calls, std::atomic<int>& calls) {
  return [good_calls, &calls](BundleAdjustmentProblem& problem, const PinholeCamera& camera,
                              const BundleAdjustmentOptions& options) {
    if (++calls > good_calls) throw std::runtime_error(kInjectedError);
    return solveLocalBundleAdjustment(problem, camera, options);
  };
}

// The failing optimisation's exception reaches the tracking thread with its message through the next call (inline:
// keyframeInserted itself; background: flush), is not lost afterwards (every later call reports it, as LoopCloser
// does), leaves the map as the last good optimisation did, stops all further optimisation, and the destructor
// returns. Every call runs under a deadlock guard.
TEST(Backend, AnOptimisationErrorReachesTrackingAndTheBackendStopsCleanly) {
  const Scene scene = makeScene();
  for (const bool background : {false, true}) {
    SCOPED_TRACE(background ? "background thread" : "inline");
    Map map;
    fillMap(map, scene);
    std::atomic<int> calls{0};
    BackendOptions options;
    options.background_thread = background;
    options.solver = failingAfter(1, calls);
    auto backend = std::make_unique<Backend>(map, scene.camera, options);
    returnsWithoutDeadlock("the good optimisation", [&] {
      backend->keyframeInserted();
      backend->flush();
    });
    ASSERT_EQ(backend->optimizationsRun(), 1u);
    const std::uint64_t revision = map.revision();

    // Inline, the request itself fails; in the background it returns and the error waits for the next call.
    const std::string from_request = errorOf("keyframeInserted", [&] { backend->keyframeInserted(); });
    const std::string from_flush = errorOf("flush", [&] { backend->flush(); });
    EXPECT_EQ(background ? from_flush : from_request, kInjectedError);
    if (background) {
      EXPECT_EQ(from_request, "") << "nothing had failed yet when it was asked";
    }
    EXPECT_EQ(calls.load(), 2) << "the failing optimisation ran once";

    // Not lost once reported, and nothing more is optimised.
    EXPECT_EQ(errorOf("a later keyframeInserted", [&] { backend->keyframeInserted(); }), kInjectedError);
    EXPECT_EQ(errorOf("a later flush", [&] { backend->flush(); }), kInjectedError);
    EXPECT_EQ(calls.load(), 2);
    EXPECT_EQ(backend->optimizationsRun(), 1u);
    EXPECT_EQ(map.revision(), revision) << "the failed optimisation wrote nothing back";
    returnsWithoutDeadlock("the destructor", [&] { backend.reset(); });
  }
}

// Requests that arrive while the optimisation that will fail is running are dropped, not run on a map the failure
// may have left half-updated; the error is reported once the request is flushed. The solver blocks until released,
// so the order is forced, not left to the scheduler.
TEST(Backend, ARequestArrivingWhileTheFailingOptimisationRunsIsDropped) {
  const Scene scene = makeScene();
  Map map;
  fillMap(map, scene);
  std::atomic<int> calls{0};
  std::promise<void> entered, release;
  std::shared_future<void> released = release.get_future().share();
  BackendOptions options;
  options.solver = [&](BundleAdjustmentProblem&, const PinholeCamera&,
                       const BundleAdjustmentOptions&) -> BundleAdjustmentSummary {
    if (++calls == 1) entered.set_value();
    released.wait();
    throw std::runtime_error(kInjectedError);
  };
  auto backend = std::make_unique<Backend>(map, scene.camera, options);
  backend->keyframeInserted();
  entered.get_future().wait();
  EXPECT_EQ(errorOf("keyframeInserted while optimising", [&] { backend->keyframeInserted(); }), "");
  release.set_value();
  EXPECT_EQ(errorOf("flush", [&] { backend->flush(); }), kInjectedError);
  EXPECT_EQ(calls.load(), 1) << "the request pending at the error was run";
  returnsWithoutDeadlock("the destructor", [&] { backend.reset(); });
  EXPECT_EQ(calls.load(), 1);
}

// The destructor of a backend whose error was never reported (no flush, requests still pending) returns without
// throwing or terminating, and finishes no work after the error (errors are dropped there, as documented).
TEST(Backend, TheDestructorReturnsWithAnUnreportedError) {
  const Scene scene = makeScene();
  Map map;
  fillMap(map, scene);
  const std::uint64_t revision = map.revision();
  std::atomic<int> calls{0};
  BackendOptions options;
  options.solver = failingAfter(0, calls);
  auto backend = std::make_unique<Backend>(map, scene.camera, options);
  for (int i = 0; i < 3; ++i) errorOf("keyframeInserted", [&] { backend->keyframeInserted(); });
  returnsWithoutDeadlock("the destructor", [&] { backend.reset(); });
  EXPECT_EQ(calls.load(), 1) << "pending work is finished before stopping, but none after an error";
  EXPECT_EQ(map.revision(), revision);
}

// A replaced solver is checked like any input: reporting success with a solution that does not fit the window
// (here no covariances and no outlier flags) is an error naming what is missing, and the map is left alone.
TEST(Backend, ASolverWhoseSolutionDoesNotFitTheWindowIsAnError) {
  const Scene scene = makeScene();
  Map map;
  fillMap(map, scene);
  const std::uint64_t revision = map.revision();
  BackendOptions options = inlineOptions();
  options.solver = [](BundleAdjustmentProblem&, const PinholeCamera&, const BundleAdjustmentOptions&) {
    BundleAdjustmentSummary summary;
    summary.ok = true;
    return summary;
  };
  Backend backend(map, scene.camera, options);
  const std::string error = errorOf("keyframeInserted", [&] { backend.keyframeInserted(); });
  EXPECT_NE(error.find("0 point covariances for " + std::to_string(scene.true_points.size())), std::string::npos)
      << error;
  EXPECT_EQ(map.revision(), revision);
}

}  // namespace
