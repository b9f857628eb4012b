#pragma once
// Flags matches on moving objects: each match gets a distance that is small
// for a static point and a flag when the distance exceeds what noise explains.

#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "weighted_icp/core/camera.h"
#include "weighted_icp/frontend/geometry/depth_noise_model.h"

namespace weighted_icp::frontend {

struct DynamicPointFilterOptions {
  double min_displacement_m = 0.03;
  double depth_sigmas = 3.0;
  double max_epipolar_px = 2.0;
};

/// |T_wc^-1 X_w - X_c measured| per match, in metres; NaN where an input is
/// not finite or the measured depth is not positive. Throws
/// std::invalid_argument when the sizes differ.
std::vector<double> displacementDistances(const std::vector<Eigen::Vector3d>& points_world,
                                          const std::vector<Eigen::Vector3d>& points_camera_measured,
                                          const Eigen::Isometry3d& pose_wc);

/// Flags a match whose displacement exceeds max(min_displacement_m,
/// depth_sigmas * sigma_z(measured z)). Matches without a distance (NaN) are
/// not flagged: there is no evidence that they move.
std::vector<bool> flagDynamicByDisplacement(const std::vector<Eigen::Vector3d>& points_world,
                                            const std::vector<Eigen::Vector3d>& points_camera_measured,
                                            const Eigen::Isometry3d& pose_wc, const DepthNoiseModel& noise,
                                            const DynamicPointFilterOptions& options = {});

/// The fundamental matrix F = K^-T [t]x R K^-1 of the motion x2 = R x1 + t (pose_2_in_1 inverted), with the
/// translation normalised: pixel 2 of a static point lies on the line F pixel1. Zero when the motion has no
/// translation (no epipolar geometry).
Eigen::Matrix3d fundamentalMatrix(const Eigen::Isometry3d& pose_2_in_1, const PinholeCamera& camera);

/// Distance in pixels of `pixel` to the image line (a, b, c), a u + b v + c = 0; NaN for a degenerate line.
double distanceToLine(const Eigen::Vector3d& line, const Eigen::Vector2d& pixel);

/// Symmetric epipolar distance per match, in pixels: the root mean square of
/// the distance of pixel 2 to the epipolar line of pixel 1 and of pixel 1 to
/// the line of pixel 2, under F = K^-T [t]x R K^-1 of the known motion. NaN
/// where a pixel is not finite, and everywhere when the motion has no
/// translation (no epipolar geometry). A point moving within its epipolar
/// plane keeps a zero distance: this test cannot see it. Throws
/// std::invalid_argument when the sizes differ or the intrinsics are invalid.
std::vector<double> symmetricEpipolarDistances(const std::vector<Eigen::Vector2d>& pixels1,
                                               const std::vector<Eigen::Vector2d>& pixels2,
                                               const Eigen::Isometry3d& pose_2_in_1, const PinholeCamera& camera);

/// Flags a match whose symmetric epipolar distance exceeds max_epipolar_px;
/// with pixel noise sigma on both images a static point's distance has a
/// standard deviation of about sqrt(2) sigma.
std::vector<bool> flagDynamicByEpipolarDistance(const std::vector<Eigen::Vector2d>& pixels1,
                                                const std::vector<Eigen::Vector2d>& pixels2,
                                                const Eigen::Isometry3d& pose_2_in_1, const PinholeCamera& camera,
                                                const DynamicPointFilterOptions& options = {});

}  // namespace weighted_icp::frontend
