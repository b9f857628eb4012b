#pragma once
// Information of the pose graph's odometry edges estimated from tracking: how
// well two consecutive keyframes' relative pose is held by the landmarks they
// observe (the Gauss-Newton system of their reprojection residuals, whitened
// by the measured pixel noise, with the landmarks as unknowns held by their
// map covariances), instead of one noise model for every edge.

#include <cstddef>
#include <optional>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "weighted_icp/core/camera.h"
#include "weighted_icp/mapping/keyframe_snapshot.h"
#include "weighted_icp/mapping/pose_graph.h"

namespace weighted_icp::mapping {

/// @brief 6x6 covariance ordered (translation x y z, rotation x y z), as Information6d.
using Covariance6d = Eigen::Matrix<double, 6, 6>;

/// @brief How a keyframe's tracking quality becomes an odometry edge's information.
struct TrackingInformationOptions {
  /// @brief Observations farther than this from their landmark's projection (pixels) are outliers the tracker
  /// would not have used: left out of the Hessian and of the pixel noise (the tracker's RANSAC threshold).
  double inlier_px = 3.0;
  /// @brief The pixel noise is the inliers' RMS per coordinate, never below this.
  double min_pixel_sigma_px = 0.5;
  /// @brief Fewer inlier observations than this: the keyframe's pose is not held by its landmarks and the edge
  /// falls back to the noise model.
  std::size_t min_observations = 12;
  /// @brief Variance factor on the relative pose's covariance. The reprojection Hessian describes only random pixel
  /// noise; a real sensor adds errors it cannot see (calibration, depth bias, rolling shutter, colour-depth timing).
  /// On synthetic loops 1 was right (the keyframe-to-keyframe errors over the edges' standard deviations had per-axis
  /// RMS 0.47-0.76 bright, 0.94-1.19 dim). On real revisits (TUM fr3 teddy there and back, `wicp_make_variant
  /// --variant there-and-back`, seven variants) the pose graph's consistency test refused about half of the true
  /// loops with 1, within a session and between its halves merged (cost rises up to 180 against the gate's 22.5);
  /// 10, with the loop's own LoopVerifierOptions::covariance_inflation, is the smallest round factor that refused
  /// none of them, and changed no synthetic result beyond its scatter (docs/mapping.md, "Real revisits").
  double covariance_inflation = 10.0;
  /// @brief Added in quadrature to every edge's standard deviations (metres, radians), so that no edge claims
  /// sub-millimetre accuracy.
  double translation_floor_m = 0.0005;
  double rotation_floor_rad = 0.0002;
};

/// @brief The covariance of a keyframe's pose given the landmarks it observes, for the perturbation
/// pose_wc * Exp(delta) (translation in the keyframe's camera frame, rotation vector on the right), without the
/// inflation: the inverse of sum J^T W J over its inlier observations. Zero observations, too few or a singular
/// Hessian give nothing.
/// @param map keyframes and map points (world positions, covariances, observations)
/// @param keyframe the keyframe; unknown gives nothing
/// @param camera the undistorted pinhole model its pixels were measured with
/// @param options thresholds
std::optional<Covariance6d> keyframePoseCovariance(const KeyframeSnapshot& map, frontend::KeyframeId keyframe,
                                                   const PinholeCamera& camera,
                                                   const TrackingInformationOptions& options = {});

/// @brief The information of the odometry edge a -> b (to_in_from = a^-1 b) from both keyframes' pose covariances
/// (first-order propagation to the relative pose, as the pose graph's residual orders it), times the inflation,
/// plus the floors.
/// @param a_wc pose of the older keyframe
/// @param covariance_a its keyframePoseCovariance
/// @param b_wc pose of the newer keyframe
/// @param covariance_b its keyframePoseCovariance
/// @param options inflation and floors
Information6d trackedOdometryInformation(const Eigen::Isometry3d& a_wc, const Covariance6d& covariance_a,
                                         const Eigen::Isometry3d& b_wc, const Covariance6d& covariance_b,
                                         const TrackingInformationOptions& options = {});

/// @brief The covariance of the relative pose a -> b given the landmarks either keyframe observes, ordered as the
/// pose graph's odometry residual, without the inflation. Both poses and every landmark are unknowns of one
/// Gauss-Newton system (the landmarks held by their map covariances as a prior); eliminating the landmarks leaves
/// the poses' joint covariance, in which a landmark both keyframes see moves both alike, so its error cancels in
/// the relative pose instead of being added once per keyframe (what keyframePoseCovariance twice, propagated by
/// trackedOdometryInformation, does). A landmark only one of them sees holds that keyframe only when a keyframe
/// older than the newer of the two also observes it: one mapped from the keyframe itself, or seen since by later
/// keyframes only, would hold it to its own measurement and is left out. Unknown keyframes, a == b, too few inliers
/// in either, no inlier landmark both observe (their poses were not measured against each other) or a singular
/// system give nothing.
/// @param map keyframes and map points (world positions, covariances, observations)
/// @param a the older keyframe
/// @param b the newer keyframe
/// @param camera the undistorted pinhole model their pixels were measured with
/// @param options thresholds
std::optional<Covariance6d> relativePoseCovariance(const KeyframeSnapshot& map, frontend::KeyframeId a,
                                                   frontend::KeyframeId b, const PinholeCamera& camera,
                                                   const TrackingInformationOptions& options = {});

/// @brief relativePoseCovariance of every pair of consecutive keyframes, each keyframe's observations gathered once
/// (what a loop closure recomputes for all its odometry edges).
/// @param map keyframes and map points
/// @param keyframes the keyframes in order
/// @param camera the undistorted pinhole model their pixels were measured with
/// @param options thresholds
/// @return entry i: the edge keyframes[i-1] -> keyframes[i]; entry 0 is empty, as is an edge either of whose
/// keyframes is unknown or not held by its landmarks
std::vector<std::optional<Covariance6d>> odometryEdgeCovariances(const KeyframeSnapshot& map,
                                                                 const std::vector<frontend::KeyframeId>& keyframes,
                                                                 const PinholeCamera& camera,
                                                                 const TrackingInformationOptions& options = {});

/// @brief The information of an odometry edge from its relativePoseCovariance: times the inflation, plus the floors.
/// @param relative_covariance the edge's covariance, ordered as the pose graph's residual
/// @param options inflation and floors
Information6d relativeOdometryInformation(const Covariance6d& relative_covariance,
                                          const TrackingInformationOptions& options = {});

}  // namespace weighted_icp::mapping
