#include "weighted_icp/frontend/geometry/local_bundle_adjustment.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>

#include <ceres/loss_function.h>
#include <ceres/ordered_groups.h>
#include <ceres/problem.h>
#include <ceres/solver.h>
#include <Eigen/Eigenvalues>

#include "input_checks.h"
#include "solver_options.h"
#include "weighted_icp/frontend/geometry/reprojection_residual.h"

namespace weighted_icp::frontend {

namespace {

constexpr double kOutlierHuberFactor = 3.0;
constexpr double kChi2TwoDof95 = 5.991, kChi2ThreeDof95 = 7.815;

std::optional<std::string> problemDescription(const BundleAdjustmentProblem& problem, const PinholeCamera& camera,
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
  return bundleAdjustmentOptionsProblem(options);
}

bool usesDepth(const BundleAdjustmentProblem::Observation& observation, const BundleAdjustmentOptions& options) {
  return options.use_depth && std::isfinite(observation.depth) && observation.depth > 0;
}

/// Reprojection error in pixels, or NaN behind the camera.
double reprojectionError(const PinholeCamera& camera, const PoseParameters& pose, const Eigen::Vector3d& point_world,
                         const Eigen::Vector2d& pixel) {
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

/// The solve's working copy of the unknowns (Ceres optimises these in place).
struct Unknowns {
  std::vector<PoseParameters> poses;
  std::vector<Eigen::Vector3d> points;
};

/// Robust thresholds on whitened residuals: one in sigmas for a pixel-only
/// block; an RGB-D block has three residuals, so its threshold grows with the
/// ratio of the 95 % chi-square quantiles (3 vs 2 dof) to downweight inliers
/// equally often. Infinity: least squares.
struct HuberThresholds {
  double pixel;
  double rgbd;
};

/// The Ceres problem and what building it learnt. The losses are declared
/// first so that they outlive the problem, which does not own them.
struct SolverProblem {
  std::unique_ptr<ceres::LossFunction> pixel_loss, rgbd_loss;
  ceres::Problem problem;
  std::shared_ptr<ceres::ParameterBlockOrdering> ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  std::vector<bool> pose_observed, point_observed;

  static ceres::Problem::Options problemOptions() {
    ceres::Problem::Options options;
    options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;  // the losses are shared by many blocks
    return options;
  }
  SolverProblem() : problem(problemOptions()) {}
};

HuberThresholds huberThresholds(const BundleAdjustmentOptions& options) {
  const double pixel_huber = options.huber_px / options.noise.pixel_sigma;
  return {pixel_huber, pixel_huber * std::sqrt(kChi2ThreeDof95 / kChi2TwoDof95)};
}

Unknowns initialUnknowns(const BundleAdjustmentProblem& problem) {
  Unknowns unknowns;
  unknowns.poses.reserve(problem.poses_wc.size());
  for (const auto& pose_wc : problem.poses_wc) unknowns.poses.push_back(PoseParameters::fromPoseWc(pose_wc));
  unknowns.points = problem.points_world;
  return unknowns;
}

/// Reprojection error of each observation at `unknowns`; NaN behind the camera
/// or where `usable` (if given) is NaN.
std::vector<double> reprojectionErrors(const BundleAdjustmentProblem& problem, const PinholeCamera& camera,
                                       const Unknowns& unknowns, const std::vector<double>* usable = nullptr) {
  std::vector<double> errors(problem.observations.size(), std::numeric_limits<double>::quiet_NaN());
  for (std::size_t i = 0; i < problem.observations.size(); ++i) {
    if (usable && std::isnan((*usable)[i])) continue;
    const auto& observation = problem.observations[i];
    errors[i] = reprojectionError(camera, unknowns.poses[observation.pose], unknowns.points[observation.point],
                                  observation.pixel);
  }
  return errors;
}

/// Pose and point blocks (points eliminated first by DENSE_SCHUR), one
/// residual block per observation with a reprojection at the start.
void buildProblem(const BundleAdjustmentProblem& problem, const PinholeCamera& camera,
                  const BundleAdjustmentOptions& options, const HuberThresholds& huber,
                  const std::vector<double>& initial_errors, Unknowns& unknowns, SolverProblem& solver) {
  const auto makeLoss = [](double delta) -> std::unique_ptr<ceres::LossFunction> {
    if (!std::isfinite(delta)) return nullptr;
    return std::make_unique<ceres::HuberLoss>(delta);
  };
  solver.pixel_loss = makeLoss(huber.pixel);
  solver.rgbd_loss = makeLoss(huber.rgbd);
  constexpr int kPointGroup = 0, kPoseGroup = 1;
  auto* pose_manifold = new PoseManifold;  // the problem takes ownership, shared
  for (std::size_t k = 0; k < unknowns.poses.size(); ++k) {
    solver.problem.AddParameterBlock(unknowns.poses[k].data(), 7, pose_manifold);
    solver.ordering->AddElementToGroup(unknowns.poses[k].data(), kPoseGroup);
    if (problem.pose_fixed[k]) solver.problem.SetParameterBlockConstant(unknowns.poses[k].data());
  }
  solver.pose_observed.assign(unknowns.poses.size(), false);
  solver.point_observed.assign(unknowns.points.size(), false);
  const double pixel_sigma = options.noise.pixel_sigma;
  for (std::size_t i = 0; i < problem.observations.size(); ++i) {
    if (std::isnan(initial_errors[i])) continue;
    const auto& observation = problem.observations[i];
    PoseParameters& pose = unknowns.poses[observation.pose];
    double* point = unknowns.points[observation.point].data();
    if (!solver.point_observed[observation.point]) solver.ordering->AddElementToGroup(point, kPointGroup);
    solver.pose_observed[observation.pose] = solver.point_observed[observation.point] = true;
    if (usesDepth(observation, options))
      solver.problem.AddResidualBlock(new RgbdResidual(camera, observation.pixel, pixel_sigma, observation.depth,
                                                       options.noise.sigmaDepth(observation.depth)),
                                      solver.rgbd_loss.get(), pose.data(), point);
    else
      solver.problem.AddResidualBlock(new ReprojectionResidual(camera, observation.pixel, pixel_sigma),
                                      solver.pixel_loss.get(), pose.data(), point);
  }
}

/// Levenberg-Marquardt with a dense Schur complement; the failure, if any.
std::optional<std::string> solve(SolverProblem& solver, const BundleAdjustmentOptions& options, int& iterations) {
  ceres::Solver::Options solver_options = detail::levenbergMarquardt(options.max_iterations);
  solver_options.linear_solver_type = ceres::DENSE_SCHUR;  // a local window has few poses
  solver_options.linear_solver_ordering = solver.ordering;
  solver_options.function_tolerance = options.function_tolerance;
  solver_options.num_threads = options.threads;
  ceres::Solver::Summary solver_summary;
  ceres::Solve(solver_options, &solver.problem, &solver_summary);
  if (!solver_summary.IsSolutionUsable()) return "Ceres: " + solver_summary.message;
  iterations = solver_summary.num_successful_steps + solver_summary.num_unsuccessful_steps;
  return std::nullopt;
}

/// Flags as outliers the observations beyond kOutlierHuberFactor * huber_px
/// (or without a reprojection) after the solve; RMS before and after over the others.
void classifyOutliers(const std::vector<double>& initial_errors, const std::vector<double>& final_errors,
                      const BundleAdjustmentOptions& options, BundleAdjustmentSummary& summary) {
  summary.outlier_observations.assign(initial_errors.size(), true);
  double initial_sum = 0.0, final_sum = 0.0;
  std::size_t inlier_count = 0;
  for (std::size_t i = 0; i < initial_errors.size(); ++i) {
    const double error = final_errors[i];
    if (std::isnan(error) || error > kOutlierHuberFactor * options.huber_px) continue;
    summary.outlier_observations[i] = false;
    initial_sum += initial_errors[i] * initial_errors[i];
    final_sum += error * error;
    ++inlier_count;
  }
  if (inlier_count > 0) {
    summary.initial_rms_px = std::sqrt(initial_sum / static_cast<double>(inlier_count));
    summary.final_rms_px = std::sqrt(final_sum / static_cast<double>(inlier_count));
  }
}

/// Per point, the Gauss-Newton information from its observations with a
/// reprojection after the solve (outliers included), poses fixed, each with
/// the Huber weight the solve gave it.
std::vector<Eigen::Matrix3d> pointInformation(const BundleAdjustmentProblem& problem, const PinholeCamera& camera,
                                              const BundleAdjustmentOptions& options, const HuberThresholds& huber,
                                              const std::vector<double>& final_errors, const Unknowns& unknowns) {
  const double pixel_sigma = options.noise.pixel_sigma;
  std::vector<Eigen::Matrix3d> information(unknowns.points.size(), Eigen::Matrix3d::Zero());
  for (std::size_t i = 0; i < problem.observations.size(); ++i) {
    if (std::isnan(final_errors[i])) continue;
    const auto& observation = problem.observations[i];
    const double* blocks[] = {unknowns.poses[observation.pose].data(), unknowns.points[observation.point].data()};
    if (usesDepth(observation, options)) {
      Eigen::Vector3d residuals;
      Eigen::Matrix<double, 3, 3, Eigen::RowMajor> jacobian;
      double* jacobians[] = {nullptr, jacobian.data()};
      RgbdResidual(camera, observation.pixel, pixel_sigma, observation.depth,
                   options.noise.sigmaDepth(observation.depth))
          .Evaluate(blocks, residuals.data(), jacobians);
      information[observation.point] += huberWeight(residuals.norm(), huber.rgbd) * jacobian.transpose() * jacobian;
    } else {
      Eigen::Vector2d residuals;
      Eigen::Matrix<double, 2, 3, Eigen::RowMajor> jacobian;
      double* jacobians[] = {nullptr, jacobian.data()};
      ReprojectionResidual(camera, observation.pixel, pixel_sigma).Evaluate(blocks, residuals.data(), jacobians);
      information[observation.point] += huberWeight(residuals.norm(), huber.pixel) * jacobian.transpose() * jacobian;
    }
  }
  return information;
}

/// Copies the solution into `problem`: the poses that are free and observed, the observed points.
void writeBack(const Unknowns& unknowns, const SolverProblem& solver, BundleAdjustmentProblem& problem) {
  for (std::size_t k = 0; k < unknowns.poses.size(); ++k)
    if (!problem.pose_fixed[k] && solver.pose_observed[k]) problem.poses_wc[k] = unknowns.poses[k].poseWc();
  for (std::size_t j = 0; j < unknowns.points.size(); ++j)
    if (solver.point_observed[j]) problem.points_world[j] = unknowns.points[j];
}

}  // namespace

std::optional<std::string> bundleAdjustmentOptionsProblem(const BundleAdjustmentOptions& options) {
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

BundleAdjustmentSummary solveLocalBundleAdjustment(BundleAdjustmentProblem& problem, const PinholeCamera& camera,
                                                   const BundleAdjustmentOptions& options) {
  BundleAdjustmentSummary summary;
  if (const auto description = problemDescription(problem, camera, options)) {
    summary.failure = *description;
    return summary;
  }
  Unknowns unknowns = initialUnknowns(problem);
  // Observations of a point behind its camera have no reprojection to fit.
  const std::vector<double> initial_errors = reprojectionErrors(problem, camera, unknowns);
  if (std::all_of(initial_errors.begin(), initial_errors.end(), [](double e) { return std::isnan(e); })) {
    summary.failure = "every observed point is behind its camera";
    return summary;
  }

  const HuberThresholds huber = huberThresholds(options);
  SolverProblem solver;
  buildProblem(problem, camera, options, huber, initial_errors, unknowns, solver);
  if (const auto failure = solve(solver, options, summary.iterations)) {
    summary.failure = *failure;
    return summary;
  }

  const std::vector<double> final_errors = reprojectionErrors(problem, camera, unknowns, &initial_errors);
  classifyOutliers(initial_errors, final_errors, options, summary);
  summary.point_covariances.reserve(unknowns.points.size());
  for (const auto& information : pointInformation(problem, camera, options, huber, final_errors, unknowns))
    summary.point_covariances.push_back(covarianceFromInformation(information));
  writeBack(unknowns, solver, problem);
  summary.ok = true;
  return summary;
}

}  // namespace weighted_icp::frontend
