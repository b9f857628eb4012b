// Local bundle adjustment on synthetic windows with known truth, and the
// analytic Jacobians of its residuals against numeric differentiation.

#include <chrono>
#include <ctime>
#include <random>

#include <ceres/gradient_checker.h>
#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>

#include "test_geometry_scene.h"
#include "weighted_icp/frontend/geometry/local_bundle_adjustment.h"
#include "weighted_icp/frontend/geometry/reprojection_residual.h"
#include "weighted_icp/registration/rigid_motion.h"

namespace {

using namespace weighted_icp;
using namespace weighted_icp::frontend;
using weighted_icp::testing::gaussianPixel;
using weighted_icp::testing::makePose;
using weighted_icp::testing::perturbPose;
using weighted_icp::testing::pointsInView;
using weighted_icp::testing::syntheticCamera;

struct Window {
  BundleAdjustmentProblem problem;  // noisy
  std::vector<Eigen::Isometry3d> true_poses;
  std::vector<Eigen::Vector3d> true_points;
  std::vector<int> views_of_point;
};

/// Keyframes moving sideways and turning, all looking at one volume 2-5 m
/// ahead. Every point is observed (pixel and depth, with noise) by each
/// keyframe that sees it, or by the first `few_views` when it is among the
/// first `few_view_points`. Pose 0 is fixed and exact; the others and the
/// points start perturbed.
Window makeWindow(int num_poses, int num_points, unsigned seed, int few_view_points = 0, int few_views = 2) {
  std::mt19937 rng(seed);
  const auto camera = syntheticCamera();
  const DepthNoiseModel noise;
  constexpr double kPixelSigma = 0.5;
  Window window;
  for (int k = 0; k < num_poses; ++k) window.true_poses.push_back(makePose({0, 2.0 * k, 0}, {0.08 * k, 0, 0.02 * k}));
  window.true_points = pointsInView(camera, window.true_poses[num_poses / 2], num_points, 2.0, 5.0, rng);

  std::normal_distribution<double> gauss(0.0, 1.0);
  for (int j = 0; j < num_points; ++j) {
    int views = 0;
    const int max_views = j < few_view_points ? few_views : num_poses;
    for (int k = 0; k < num_poses && views < max_views; ++k) {
      const Eigen::Vector3d in_camera = window.true_poses[k].inverse() * window.true_points[j];
      const Eigen::Vector2d pixel = camera.project(in_camera);
      if (!camera.inImage(pixel)) continue;
      const double depth = in_camera.z() + noise.sigmaDepth(in_camera.z()) * gauss(rng);
      window.problem.observations.push_back({k, j, pixel + gaussianPixel(kPixelSigma, rng), depth});
      ++views;
    }
    window.views_of_point.push_back(views);
  }
  for (int k = 0; k < num_poses; ++k) {
    window.problem.pose_fixed.push_back(k == 0);
    window.problem.poses_wc.push_back(k == 0 ? window.true_poses[k]
                                             : perturbPose(window.true_poses[k], 0.02, 1.0, rng));
  }
  for (const auto& point : window.true_points)
    window.problem.points_world.push_back(point + 0.03 * Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng)));
  return window;
}

BundleAdjustmentOptions halfPixelOptions() {
  BundleAdjustmentOptions options;
  options.noise.pixel_sigma = 0.5;
  options.huber_px = 1.0;  // 2 sigma
  return options;
}

struct PoseErrors {
  double rotation_deg = 0, translation_m = 0;
};

PoseErrors meanPoseError(const std::vector<Eigen::Isometry3d>& poses, const std::vector<Eigen::Isometry3d>& truth) {
  PoseErrors errors;
  for (std::size_t k = 1; k < poses.size(); ++k) {
    errors.rotation_deg += rotationErrorDeg(poses[k], truth[k]) / (poses.size() - 1);
    errors.translation_m += translationError(poses[k], truth[k]) / (poses.size() - 1);
  }
  return errors;
}

TEST(LocalBundleAdjustment, ReducesPoseErrorAndReprojectionKeepingTheFixedPose) {
  Window window = makeWindow(5, 300, 41);
  const Eigen::Isometry3d fixed_before = window.problem.poses_wc[0];
  const PoseErrors before = meanPoseError(window.problem.poses_wc, window.true_poses);
  const BundleAdjustmentSummary summary =
      solveLocalBundleAdjustment(window.problem, syntheticCamera(), halfPixelOptions());
  ASSERT_TRUE(summary.ok) << summary.failure;
  const PoseErrors after = meanPoseError(window.problem.poses_wc, window.true_poses);
  double point_error = 0;
  for (std::size_t j = 0; j < window.true_points.size(); ++j)
    point_error += (window.problem.points_world[j] - window.true_points[j]).norm() / window.true_points.size();
  std::cout << "BA 5 poses x 300 points: pose error " << before.rotation_deg << " deg " << before.translation_m * 1000
            << " mm -> " << after.rotation_deg << " deg " << after.translation_m * 1000 << " mm; RMS "
            << summary.initial_rms_px << " -> " << summary.final_rms_px << " px in " << summary.iterations
            << " iterations; mean point error " << point_error * 1000 << " mm\n";
  EXPECT_TRUE(window.problem.poses_wc[0].matrix() == fixed_before.matrix());
  EXPECT_LT(after.rotation_deg, 0.1 * before.rotation_deg);
  EXPECT_LT(after.translation_m, 0.1 * before.translation_m);
  EXPECT_LT(summary.final_rms_px, 0.1 * summary.initial_rms_px);
  EXPECT_LT(summary.final_rms_px, 1.0);  // 0.5 px per axis: about 0.7 px
  EXPECT_LT(point_error, 0.01);
  for (const bool outlier : summary.outlier_observations) EXPECT_FALSE(outlier);
}

TEST(LocalBundleAdjustment, FlagsOutlierObservations) {
  Window window = makeWindow(5, 300, 42);
  std::mt19937 rng(43);
  std::uniform_real_distribution<double> offset(15.0, 40.0);
  std::vector<bool> corrupted(window.problem.observations.size(), false);
  for (std::size_t i = 0; i < corrupted.size(); i += 20) {  // 5 %
    window.problem.observations[i].pixel += Eigen::Vector2d(offset(rng), -offset(rng));
    corrupted[i] = true;
  }
  const BundleAdjustmentSummary summary =
      solveLocalBundleAdjustment(window.problem, syntheticCamera(), halfPixelOptions());
  ASSERT_TRUE(summary.ok) << summary.failure;
  ASSERT_EQ(summary.outlier_observations.size(), corrupted.size());
  int caught = 0, corrupted_count = 0, false_flags = 0;
  for (std::size_t i = 0; i < corrupted.size(); ++i) {
    corrupted_count += corrupted[i] ? 1 : 0;
    caught += corrupted[i] && summary.outlier_observations[i] ? 1 : 0;
    false_flags += !corrupted[i] && summary.outlier_observations[i] ? 1 : 0;
  }
  const PoseErrors after = meanPoseError(window.problem.poses_wc, window.true_poses);
  std::cout << "BA with 5 % outliers: " << caught << "/" << corrupted_count << " flagged, " << false_flags
            << " clean observations flagged; pose error " << after.rotation_deg << " deg " << after.translation_m * 1000
            << " mm; inlier RMS " << summary.final_rms_px << " px\n";
  EXPECT_EQ(caught, corrupted_count);
  EXPECT_LE(false_flags, 0.005 * corrupted.size());
  EXPECT_LT(after.translation_m, 0.003);
}

TEST(LocalBundleAdjustment, PointCovariancesArePositiveDefiniteAndShrinkWithMoreViews) {
  Window window = makeWindow(5, 300, 44, /*few_view_points=*/150, /*few_views=*/2);
  const BundleAdjustmentSummary summary =
      solveLocalBundleAdjustment(window.problem, syntheticCamera(), halfPixelOptions());
  ASSERT_TRUE(summary.ok) << summary.failure;
  ASSERT_EQ(summary.point_covariances.size(), window.true_points.size());
  double trace_two = 0, trace_five = 0;
  int count_two = 0, count_five = 0;
  for (std::size_t j = 0; j < summary.point_covariances.size(); ++j) {
    const Eigen::Matrix3d& covariance = summary.point_covariances[j];
    EXPECT_TRUE(covariance.isApprox(covariance.transpose(), 1e-12));
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(covariance).eigenvalues().minCoeff(), 0.0);
    if (window.views_of_point[j] == 2) trace_two += covariance.trace(), ++count_two;
    if (window.views_of_point[j] == 5) trace_five += covariance.trace(), ++count_five;
  }
  ASSERT_GT(count_two, 50);
  ASSERT_GT(count_five, 50);
  trace_two /= count_two;
  trace_five /= count_five;
  std::cout << "point covariance trace: seen by 2 keyframes " << trace_two << " m^2, by 5: " << trace_five << " m^2\n";
  EXPECT_LT(trace_five, 0.6 * trace_two);
}

TEST(LocalBundleAdjustment, IsDeterministic) {
  Window first = makeWindow(4, 200, 49);
  Window second = first;
  ASSERT_TRUE(solveLocalBundleAdjustment(first.problem, syntheticCamera(), halfPixelOptions()).ok);
  ASSERT_TRUE(solveLocalBundleAdjustment(second.problem, syntheticCamera(), halfPixelOptions()).ok);
  for (std::size_t k = 0; k < first.problem.poses_wc.size(); ++k)
    EXPECT_TRUE(first.problem.poses_wc[k].matrix() == second.problem.poses_wc[k].matrix());
  EXPECT_TRUE(first.problem.points_world == second.problem.points_world);
}

TEST(LocalBundleAdjustment, SevenPosesAndTwoThousandPointsTiming) {
  Window window = makeWindow(7, 2000, 45);
  const PoseErrors before = meanPoseError(window.problem.poses_wc, window.true_poses);
  const auto start = std::chrono::steady_clock::now();
  const std::clock_t cpu_start = std::clock();  // the process's CPU time: less sensitive to a busy machine
  const BundleAdjustmentSummary summary =
      solveLocalBundleAdjustment(window.problem, syntheticCamera(), halfPixelOptions());
  const double cpu_ms = 1000.0 * static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC;
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  ASSERT_TRUE(summary.ok) << summary.failure;
  const PoseErrors after = meanPoseError(window.problem.poses_wc, window.true_poses);
  std::cout << "BA 7 poses x 2000 points (" << window.problem.observations.size() << " observations with depth): " << ms
            << " ms wall, " << cpu_ms << " ms CPU, " << summary.iterations << " iterations, RMS "
            << summary.initial_rms_px << " -> " << summary.final_rms_px << " px, pose error "
            << before.translation_m * 1000 << " -> " << after.translation_m * 1000 << " mm\n";
  EXPECT_LT(after.translation_m, before.translation_m);
}

TEST(LocalBundleAdjustment, LeavesUnobservedPosesAndPointsAloneAndFlagsPointsBehindTheCamera) {
  Window window = makeWindow(3, 50, 48);
  window.problem.poses_wc.push_back(makePose({0, 90, 0}, {5, 5, 5}));  // a keyframe seeing none of the points
  window.problem.pose_fixed.push_back(false);
  window.problem.points_world.push_back({1, 2, 3});                                         // a point nobody observes
  window.problem.points_world.push_back(window.true_poses[1] * Eigen::Vector3d(0, 0, -2));  // behind camera 1
  const int behind = static_cast<int>(window.problem.points_world.size()) - 1;
  window.problem.observations.push_back({1, behind, {320, 240}, 2.0});
  const auto unobserved_pose = window.problem.poses_wc.back();
  const BundleAdjustmentSummary summary =
      solveLocalBundleAdjustment(window.problem, syntheticCamera(), halfPixelOptions());
  ASSERT_TRUE(summary.ok) << summary.failure;
  EXPECT_TRUE(window.problem.poses_wc.back().matrix() == unobserved_pose.matrix());
  EXPECT_TRUE(window.problem.points_world[behind - 1] == Eigen::Vector3d(1, 2, 3));
  EXPECT_TRUE(summary.outlier_observations.back());
  // Nothing constrains the unobserved point: its variance is the stated bound.
  EXPECT_DOUBLE_EQ(summary.point_covariances[behind - 1](0, 0), kUnconstrainedVariance);
}

TEST(LocalBundleAdjustment, ReportsInvalidProblems) {
  const Window valid = makeWindow(3, 20, 46);
  const auto expectFailure = [](BundleAdjustmentProblem problem, const std::string& reason,
                                const PinholeCamera& camera = syntheticCamera()) {
    const BundleAdjustmentProblem before = problem;
    const BundleAdjustmentSummary summary = solveLocalBundleAdjustment(problem, camera);
    EXPECT_FALSE(summary.ok);
    EXPECT_NE(summary.failure.find(reason), std::string::npos) << summary.failure;
    for (std::size_t k = 0; k < problem.poses_wc.size(); ++k)
      EXPECT_TRUE(problem.poses_wc[k].matrix() == before.poses_wc[k].matrix());
  };
  BundleAdjustmentProblem no_fixed = valid.problem;
  no_fixed.pose_fixed.assign(3, false);
  expectFailure(no_fixed, "no fixed pose");
  BundleAdjustmentProblem flags = valid.problem;
  flags.pose_fixed.pop_back();
  expectFailure(flags, "fixed flags");
  BundleAdjustmentProblem index = valid.problem;
  index.observations[3].point = 20;
  expectFailure(index, "out of range");
  BundleAdjustmentProblem nan_point = valid.problem;
  nan_point.points_world[5].y() = std::nan("");
  expectFailure(nan_point, "point 5");
  expectFailure(valid.problem, "intrinsics", PinholeCamera{});
  BundleAdjustmentProblem empty = valid.problem;
  empty.observations.clear();
  expectFailure(empty, "no observation");
}

/// Analytic against numeric Jacobians in the tangent spaces (the pose's 6);
/// absolute tolerance, since some entries are exactly zero.
void expectJacobiansMatch(const ceres::CostFunction& cost, const std::vector<const ceres::Manifold*>& manifolds,
                          const double* const* parameters) {
  ceres::GradientChecker::ProbeResults results;
  ceres::GradientChecker(&cost, &manifolds, {}).Probe(parameters, 1e-6, &results);
  ASSERT_TRUE(results.return_value);
  for (std::size_t block = 0; block < results.local_jacobians.size(); ++block) {
    const auto& numeric = results.local_numeric_jacobians[block];
    EXPECT_LT((results.local_jacobians[block] - numeric).norm(), 1e-6 * numeric.norm()) << "block " << block;
  }
}

TEST(ReprojectionResiduals, AnalyticJacobiansMatchNumericDifferentiation) {
  const auto camera = syntheticCamera();
  const Eigen::Isometry3d pose_wc = makePose({20, -35, 10}, {0.4, -0.3, 0.2});
  const PoseParameters pose = PoseParameters::fromPoseWc(pose_wc);
  const Eigen::Vector3d point = pose_wc * Eigen::Vector3d(0.3, -0.2, 2.5);
  const Eigen::Vector2d pixel = camera.project(pose.toCamera(point)) + Eigen::Vector2d(3, -2);
  const double* parameters[] = {pose.data(), point.data()};

  const PoseManifold manifold;
  expectJacobiansMatch(ReprojectionResidual(camera, pixel, 0.5), {&manifold, nullptr}, parameters);
  expectJacobiansMatch(RgbdResidual(camera, pixel, 0.5, 2.4, 0.01), {&manifold, nullptr}, parameters);
  expectJacobiansMatch(PoseOnlyReprojectionResidual(camera, point, pixel, 0.5), {&manifold}, parameters);
}

}  // namespace
