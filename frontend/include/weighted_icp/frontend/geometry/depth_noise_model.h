#pragma once
// Structured-light depth noise and the uncertainty of back-projected points.

#include <vector>

#include <Eigen/Core>

#include "weighted_icp/core/camera.h"

namespace weighted_icp::frontend {

/// Noise of one RGB-D measurement: pixel position and depth, independent.
struct DepthNoiseModel {
  /// sigma_z = c z^2: disparity noise of a Kinect-like sensor grows with the
  /// square of depth (Khoshelham & Elberink 2012).
  double depth_sigma_coefficient = 0.0015;
  double pixel_sigma = 1.0;

  double sigmaDepth(double z) const;
};

/// Covariance of backProject(u, v, z) in the camera frame from independent
/// pixel and depth noise, by first-order propagation J diag(s_u^2, s_v^2, s_z^2) J^T.
/// Throws std::invalid_argument for a non-positive or non-finite z, invalid
/// intrinsics or non-positive noise.
Eigen::Matrix3d pointCovarianceCamera(const PinholeCamera& camera, double u, double v, double z,
                                      const DepthNoiseModel& noise);

/// Information-weighted fusion of independent estimates of one point.
struct FusedPoint {
  Eigen::Vector3d position;
  Eigen::Matrix3d covariance;
};

/// C = (sum C_i^-1)^-1, x = C sum C_i^-1 x_i. Throws std::invalid_argument when
/// there is no estimate, the sizes differ, a value is not finite or a
/// covariance is not symmetric positive definite.
FusedPoint fusePointEstimates(const std::vector<Eigen::Vector3d>& positions,
                              const std::vector<Eigen::Matrix3d>& covariances);

}  // namespace weighted_icp::frontend
