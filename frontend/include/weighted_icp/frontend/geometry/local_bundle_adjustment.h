#pragma once
// Sliding-window bundle adjustment of keyframe poses and landmarks (Ceres,
// Levenberg-Marquardt, Huber, Schur elimination of the points), with measured
// depth as a third residual of an observation's block. Runs in the back end's
// thread; everything it needs is in its arguments.

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "weighted_icp/core/camera.h"
#include "weighted_icp/frontend/geometry/depth_noise_model.h"

namespace weighted_icp::frontend {

struct BundleAdjustmentProblem {
  std::vector<Eigen::Isometry3d> poses_wc;
  std::vector<bool> pose_fixed;  // at least one fixed (the oldest) to remove the gauge freedom
  std::vector<Eigen::Vector3d> points_world;
  struct Observation {
    int pose;
    int point;
    Eigen::Vector2d pixel;
    double depth = 0.0;  // metres; 0 (or not finite) = none
  };
  std::vector<Observation> observations;
};

struct BundleAdjustmentOptions {
  /// Robust threshold of an observation, in pixels: huber_px / pixel_sigma
  /// sigmas on the whitened reprojection; an observation with depth (3
  /// residuals) gets that times sqrt(chi2_3 / chi2_2) at 95 %, so inliers are
  /// downweighted equally often. Infinity gives plain least squares.
  double huber_px = 2.0;
  int max_iterations = 10;
  bool use_depth = true;
  DepthNoiseModel noise;
  int threads = 1;  // more threads may change the last bits of the result
  /// Stop when an iteration lowers the cost by less than this fraction: with
  /// N residuals the cost itself varies by ~1/sqrt(N) (> 5e-3 for N < 40000)
  /// from one noise draw to the next, so smaller gains move nothing that
  /// matters (Ceres' default, 1e-6, takes two more iterations on 7 x 2000).
  double function_tolerance = 1e-4;
};

struct BundleAdjustmentSummary {
  bool ok = false;
  std::string failure;
  /// RMS reprojection error before and after, both over the observations not
  /// flagged as outliers, so gross outliers do not hide the fit.
  double initial_rms_px = 0;
  double final_rms_px = 0;
  int iterations = 0;
  /// Reprojection > 3 * huber_px after the solve, or the point behind its camera.
  std::vector<bool> outlier_observations;
  /// Per point: the inverse of the point block of the Gauss-Newton information
  /// at the solution from its own (Huber-weighted) observations with the poses
  /// held fixed. Directions nothing constrains (a point seen once without
  /// depth) get a variance of kUnconstrainedVariance.
  std::vector<Eigen::Matrix3d> point_covariances;
};

/// Variance (m^2) reported along a direction no observation constrains.
inline constexpr double kUnconstrainedVariance = 1e6;

/// @brief What is wrong with `options` (a threshold not positive, no thread...), nullopt when they are usable.
/// @param options the options to check
std::optional<std::string> bundleAdjustmentOptionsProblem(const BundleAdjustmentOptions& options);

/// Updates the poses that are not fixed and the observed points in place, only
/// when the solve succeeds. Observations of a point behind its camera at the
/// start are left out (and flagged). Invalid input (sizes, indices, non-finite
/// values, no fixed pose, bad options) gives ok = false with the reason.
/// The pixels are undistorted: only fx fy cx cy of `camera` are used.
BundleAdjustmentSummary solveLocalBundleAdjustment(BundleAdjustmentProblem& problem, const PinholeCamera& camera,
                                                   const BundleAdjustmentOptions& options = {});

}  // namespace weighted_icp::frontend
