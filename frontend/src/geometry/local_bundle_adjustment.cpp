#include "weighted_icp/frontend/local_bundle_adjustment.h"

#include <cmath>
#include <limits>
#include <memory>
#include <optional>

#include <Eigen/Eigenvalues>
#include <ceres/loss_function.h>
#include <ceres/ordered_groups.h>
#include <ceres/problem.h>
#include <ceres/solver.h>

#include "input_checks.h"
#include "solver_options.h"
#include "weighted_icp/frontend/reprojection_residual.h"

namespace weighted_icp::frontend {

namespace {

constexpr double kOutlierHuberFactor = 3.0;
constexpr double kChi2TwoDof95 = 5.991, kChi2ThreeDof95 = 7.815;

std::optional<std::string> problemDescription(const BundleAdjustmentProblem& problem, const io::PinholeCamera& camera,
                                              const BundleAdjustmentOptions& options) {
  if (const auto camera_problem = detail::cameraProblem(camera)) return *camera_problem;
  if (problem.poses_wc.empty()) return "no pose";
  if (problem.pose_fixed.size() != problem.poses_wc.size())
    return std::to_string(problem.poses_wc.size()) + " poses but " + std::to_string(problem.pose_fixed.size()) +
           " fixed flags";
  bool any_fixed = false;
  for (const bool fixed : problem.pose_fixed) any_fixed = any_fixed || fixed;
  if (!any_fixed) return "no fixed pose: the gauge would be free";
  for (std::size_t i = 0; i < problem.poses_wc.size(); ++i)
    if (!detail::isRigid(problem.poses_wc[i])) return "pose " + std::to_string(i) + " is not a rigid transform";
  for (std::size_t i = 0; i < problem.points_world.size(); ++i)
    if (!problem.points_world[i].allFinite()) return "point " + std::to_string(i) + " is not finite";
  if (problem.observations.empty()) return "no observation";
  const int num_poses = static_cast<int>(problem.poses_wc.size());
  const int num_points = static_cast<int>(problem.points_world.size());
  for (std::size_t i = 0; i < problem.observations.size(); ++i) {
    const auto& observation = problem.observations[i];
    if (observation.pose < 0 || observation.pose >= num_poses || observation.point < 0 ||
        observation.point >= num_points)
      return "observation " + std::to_string(i) + " refers to pose " + std::to_string(observation.pose) + " / point " +
             std::to_string(observation.point) + ", out of range";
    if (!observation.pixel.allFinite()) return "observation " + std::to_string(i) + " has a non-finite pixel";
  }
  if (!(options.huber_px > 0)) return "huber_px must be positive";
  if (options.max_iterations < 0) return "max_iterations must not be negative";
  if (options.threads < 1) return "threads must be at least 1";
  if (!(options.function_tolerance >= 0)) return "function_tolerance must not be negative";
  if (!(options.noise.pixel_sigma > 0 && std::isfinite(options.noise.pixel_sigma)))
    return "noise.pixel_sigma must be positive";
  if (options.use_depth &&
      !(options.noise.depth_sigma_coefficient > 0 && std::isfinite(options.noise.depth_sigma_coefficient)))
    return "noise.depth_sigma_coefficient must be positive";
  return std::nullopt;
}

bool usesDepth(const BundleAdjustmentProblem::Observation& observation, const BundleAdjustmentOptions& options) {
  return options.use_depth && std::isfinite(observation.depth) && observation.depth > 0;
}

/// Reprojection error in pixels, or NaN behind the camera.
double reprojectionError(const io::PinholeCamera& camera, const PoseParameters& pose,
                         const Eigen::Vector3d& point_world, const Eigen::Vector2d& pixel) {
  const Eigen::Vector3d p = pose.toCamera(point_world);
  if (p.z() < kMinPointDepth) return std::numeric_limits<double>::quiet_NaN();
  return (camera.project(p) - pixel).norm();
}

/// IRLS weight of a whitened residual of norm `r` under Huber with threshold `delta`.
double huberWeight(double r, double delta) { return r <= delta ? 1.0 : delta / r; }

/// Inverse of a 3x3 information matrix; directions with (almost) no
/// information get kUnconstrainedVariance.
Eigen::Matrix3d covarianceFromInformation(const Eigen::Matrix3d& information) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
  eigen.computeDirect(information);
  const Eigen::Vector3d variances = eigen.eigenvalues().unaryExpr(
      [](double lambda) { return lambda * kUnconstrainedVariance > 1.0 ? 1.0 / lambda : kUnconstrainedVariance; });
  const Eigen::Matrix3d covariance = eigen.eigenvectors() * variances.asDiagonal() * eigen.eigenvectors().transpose();
  return 0.5 * (covariance + covariance.transpose());
}

}  // namespace

BundleAdjustmentSummary solveLocalBundleAdjustment(BundleAdjustmentProblem& problem, const io::PinholeCamera& camera,
                                                   const BundleAdjustmentOptions& options) {
  BundleAdjustmentSummary summary;
  if (const auto description = problemDescription(problem, camera, options)) {
    summary.failure = *description;
    return summary;
  }
  const double pixel_sigma = options.noise.pixel_sigma;
  const std::size_t num_poses = problem.poses_wc.size(), num_points = problem.points_world.size(),
                    num_observations = problem.observations.size();

  std::vector<PoseParameters> poses;
  poses.reserve(num_poses);
  for (const auto& pose_wc : problem.poses_wc) poses.push_back(PoseParameters::fromPoseWc(pose_wc));
  std::vector<Eigen::Vector3d> points = problem.points_world;

  // Observations of a point behind its camera have no reprojection to fit.
  std::vector<double> initial_errors(num_observations);
  std::size_t usable = 0;
  for (std::size_t i = 0; i < num_observations; ++i) {
    const auto& observation = problem.observations[i];
    initial_errors[i] =
        reprojectionError(camera, poses[observation.pose], points[observation.point], observation.pixel);
    usable += std::isnan(initial_errors[i]) ? 0 : 1;
  }
  if (usable == 0) {
    summary.failure = "every observed point is behind its camera";
    return summary;
  }

  // One robust threshold in sigmas; an RGB-D block has three residuals, so
  // its threshold grows with the ratio of the 95 % chi-square quantiles
  // (3 vs 2 dof) to downweight inliers equally often. Infinity: least squares.
  const double pixel_huber = options.huber_px / pixel_sigma;
  const double rgbd_huber = pixel_huber * std::sqrt(kChi2ThreeDof95 / kChi2TwoDof95);
  const auto makeLoss = [](double delta) -> std::unique_ptr<ceres::LossFunction> {
    if (!std::isfinite(delta)) return nullptr;
    return std::make_unique<ceres::HuberLoss>(delta);
  };
  const std::unique_ptr<ceres::LossFunction> pixel_loss = makeLoss(pixel_huber), rgbd_loss = makeLoss(rgbd_huber);
  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;  // the losses outlive the problem
  ceres::Problem solver_problem(problem_options);

  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  // Points first: DENSE_SCHUR eliminates them and solves only for the poses.
  constexpr int kPointGroup = 0, kPoseGroup = 1;
  auto* pose_manifold = new PoseManifold;  // the problem takes ownership, shared
  for (std::size_t k = 0; k < num_poses; ++k) {
    solver_problem.AddParameterBlock(poses[k].data(), 7, pose_manifold);
    ordering->AddElementToGroup(poses[k].data(), kPoseGroup);
    if (problem.pose_fixed[k]) solver_problem.SetParameterBlockConstant(poses[k].data());
  }
  std::vector<bool> pose_observed(num_poses, false), point_observed(num_points, false);
  for (std::size_t i = 0; i < num_observations; ++i) {
    if (std::isnan(initial_errors[i])) continue;
    const auto& observation = problem.observations[i];
    PoseParameters& pose = poses[observation.pose];
    double* point = points[observation.point].data();
    if (!point_observed[observation.point]) ordering->AddElementToGroup(point, kPointGroup);
    pose_observed[observation.pose] = point_observed[observation.point] = true;
    if (usesDepth(observation, options))
      solver_problem.AddResidualBlock(new RgbdResidual(camera, observation.pixel, pixel_sigma, observation.depth,
                                                       options.noise.sigmaDepth(observation.depth)),
                                      rgbd_loss.get(), pose.data(), point);
    else
      solver_problem.AddResidualBlock(new ReprojectionResidual(camera, observation.pixel, pixel_sigma),
                                      pixel_loss.get(), pose.data(), point);
  }

  ceres::Solver::Options solver_options = detail::levenbergMarquardt(options.max_iterations);
  solver_options.linear_solver_type = ceres::DENSE_SCHUR;  // a local window has few poses
  solver_options.linear_solver_ordering = ordering;
  solver_options.function_tolerance = options.function_tolerance;
  solver_options.num_threads = options.threads;
  ceres::Solver::Summary solver_summary;
  ceres::Solve(solver_options, &solver_problem, &solver_summary);
  if (!solver_summary.IsSolutionUsable()) {
    summary.failure = "Ceres: " + solver_summary.message;
    return summary;
  }
  summary.iterations = solver_summary.num_successful_steps + solver_summary.num_unsuccessful_steps;

  summary.outlier_observations.assign(num_observations, true);
  double initial_sum = 0.0, final_sum = 0.0;
  std::size_t inlier_count = 0;
  std::vector<Eigen::Matrix3d> information(num_points, Eigen::Matrix3d::Zero());
  for (std::size_t i = 0; i < num_observations; ++i) {
    if (std::isnan(initial_errors[i])) continue;
    const auto& observation = problem.observations[i];
    const PoseParameters& pose = poses[observation.pose];
    const Eigen::Vector3d& point = points[observation.point];
    const double error = reprojectionError(camera, pose, point, observation.pixel);
    if (std::isnan(error)) continue;
    if (error <= kOutlierHuberFactor * options.huber_px) {
      summary.outlier_observations[i] = false;
      initial_sum += initial_errors[i] * initial_errors[i];
      final_sum += error * error;
      ++inlier_count;
    }

    // Gauss-Newton information of the point from this observation, poses
    // fixed, with the Huber weight the solve gave it.
    const double* blocks[] = {pose.data(), point.data()};
    if (usesDepth(observation, options)) {
      Eigen::Vector3d residuals;
      Eigen::Matrix<double, 3, 3, Eigen::RowMajor> jacobian;
      double* jacobians[] = {nullptr, jacobian.data()};
      RgbdResidual(camera, observation.pixel, pixel_sigma, observation.depth,
                   options.noise.sigmaDepth(observation.depth))
          .Evaluate(blocks, residuals.data(), jacobians);
      information[observation.point] += huberWeight(residuals.norm(), rgbd_huber) * jacobian.transpose() * jacobian;
    } else {
      Eigen::Vector2d residuals;
      Eigen::Matrix<double, 2, 3, Eigen::RowMajor> jacobian;
      double* jacobians[] = {nullptr, jacobian.data()};
      ReprojectionResidual(camera, observation.pixel, pixel_sigma).Evaluate(blocks, residuals.data(), jacobians);
      information[observation.point] += huberWeight(residuals.norm(), pixel_huber) * jacobian.transpose() * jacobian;
    }
  }
  if (inlier_count > 0) {
    summary.initial_rms_px = std::sqrt(initial_sum / static_cast<double>(inlier_count));
    summary.final_rms_px = std::sqrt(final_sum / static_cast<double>(inlier_count));
  }
  summary.point_covariances.reserve(num_points);
  for (const auto& point_information : information)
    summary.point_covariances.push_back(covarianceFromInformation(point_information));

  for (std::size_t k = 0; k < num_poses; ++k)
    if (!problem.pose_fixed[k] && pose_observed[k]) problem.poses_wc[k] = poses[k].poseWc();
  for (std::size_t j = 0; j < num_points; ++j)
    if (point_observed[j]) problem.points_world[j] = points[j];
  summary.ok = true;
  return summary;
}

}  // namespace weighted_icp::frontend
