#pragma once
// Ceres residuals shared by PnP refinement and local bundle adjustment, with
// analytic Jacobians (bundle adjustment evaluates ~10^4 of them per iteration;
// the tests check them against numeric differentiation). A pose is one
// world-to-camera block of 7: a unit quaternion q_cw (Eigen storage x y z w)
// and a translation t_cw, X_c = R(q_cw) X_w + t_cw, on PoseManifold
// (SO(3) x R^3, 6 degrees of freedom). Residuals are whitened (divided by
// their noise sigma) so pixels and depths can share one robust loss.

#include <array>

#include <ceres/manifold.h>
#include <ceres/product_manifold.h>
#include <ceres/sized_cost_function.h>
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "weighted_icp/core/camera.h"

namespace weighted_icp::frontend {

/// A point nearer the camera plane than this makes a residual fail to
/// evaluate, and Ceres rejects the step that put it there.
inline constexpr double kMinPointDepth = 1e-6;

using PoseManifold = ceres::ProductManifold<ceres::EigenQuaternionManifold, ceres::EuclideanManifold<3>>;

/// The world-to-camera parameter block of a camera-to-world pose.
struct PoseParameters {
  std::array<double, 7> values{};  // q_cw (x y z w), t_cw

  static PoseParameters fromPoseWc(const Eigen::Isometry3d& pose_wc);
  Eigen::Isometry3d poseWc() const;
  Eigen::Vector3d toCamera(const Eigen::Vector3d& point_world) const;
  double* data() { return values.data(); }
  const double* data() const { return values.data(); }
};

/// Intrinsics and one measurement of a point, shared by the residuals.
struct PixelMeasurement {
  double fx, fy, cx, cy;
  Eigen::Vector2d pixel;
  double inverse_pixel_sigma;

  PixelMeasurement(const PinholeCamera& camera, const Eigen::Vector2d& pixel, double pixel_sigma);
};

/// (project(X_c) - pixel) / pixel_sigma; blocks pose (7), X_w (3).
class ReprojectionResidual final : public ceres::SizedCostFunction<2, 7, 3> {
 public:
  ReprojectionResidual(const PinholeCamera& camera, const Eigen::Vector2d& pixel, double pixel_sigma);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  PixelMeasurement measurement_;
};

/// The reprojection residual and (z of X_c - depth) / depth_sigma in one
/// block, so one robust loss covers the whole RGB-D measurement (as ORB-SLAM's
/// RGB-D edges do) and Ceres' Schur eliminator gets uniform 3-row blocks.
/// Blocks pose (7), X_w (3).
class RgbdResidual final : public ceres::SizedCostFunction<3, 7, 3> {
 public:
  RgbdResidual(const PinholeCamera& camera, const Eigen::Vector2d& pixel, double pixel_sigma, double depth,
               double depth_sigma);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  PixelMeasurement measurement_;
  double depth_;
  double inverse_depth_sigma_;
};

/// The reprojection residual of a world point held fixed (pose-only
/// refinement); block pose (7).
class PoseOnlyReprojectionResidual final : public ceres::SizedCostFunction<2, 7> {
 public:
  PoseOnlyReprojectionResidual(const PinholeCamera& camera, const Eigen::Vector3d& point_world,
                               const Eigen::Vector2d& pixel, double pixel_sigma);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  PixelMeasurement measurement_;
  Eigen::Vector3d point_world_;
};

}  // namespace weighted_icp::frontend
