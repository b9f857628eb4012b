#pragma once
// Camera pose from matches: 3D-2D (RANSAC PnP, then robust Levenberg-Marquardt)
// and the 2D-2D fallback (essential matrix or homography) for matches without depth.

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "weighted_icp/core/camera.h"
#include "weighted_icp/frontend/geometry/depth_noise_model.h"
#include "weighted_icp/frontend/geometry/pnp_method.h"

namespace weighted_icp::frontend {

struct PnpOptions {
  /// Most RANSAC draws (OpenCV stops earlier once the best consensus gives `confidence`, so a frame whose matches
  /// are mostly right costs the same). 1000, not OpenCV's 100: in a dim, fast turn a quarter of the matches may be
  /// right, and 100 draws find an all-inlier set there with p = 32 %, 1000 with p = 98 %; tracking was lost on
  /// such frames (docs/frontend_generalisation.md).
  int ransac_iterations = 1000;
  double ransac_reprojection_px = 3.0;
  double confidence = 0.99;
  int min_inliers = 12;
  double huber_px = 2.0;
  int refine_max_iterations = 20;
  /// The solver inside RANSAC; the Huber refinement follows either.
  PnpMethod method = PnpMethod::Ap3p;
  /// The guess as a second candidate: also refine it on the matches it explains within twice
  /// `ransac_reprojection_px` and keep that pose when it ends with more inliers than RANSAC's refined pose. Off, the
  /// guess only replaces RANSAC's hypothesis when it already explains more matches within `ransac_reprojection_px`,
  /// which a guess a degree off never does (docs/frontend_generalisation.md).
  bool refine_guess = false;
};

struct PoseEstimate {
  bool ok = false;
  std::string failure;
  Eigen::Isometry3d pose_wc = Eigen::Isometry3d::Identity();
  std::vector<int> inliers;          // indices into the input, after refinement
  double rms_reprojection_px = 0.0;  // over `inliers`
  /// The pose refinement started from: RANSAC's, or the guess when the guess
  /// explained more matches.
  Eigen::Isometry3d initial_pose_wc = Eigen::Isometry3d::Identity();
  bool initial_from_guess = false;
  /// The pose came from the guess refined as a second candidate (PnpOptions::refine_guess).
  bool refined_from_guess = false;
};

/// RANSAC PnP (OpenCV, AP3P minimal sets, EPnP on the consensus), then
/// Levenberg-Marquardt on the inliers with Huber-weighted reprojection
/// residuals (Ceres); the final inliers are re-selected by reprojection error
/// (<= ransac_reprojection_px, in front of the camera) after refinement.
/// `guess_wc` (e.g. the constant-velocity prediction) competes with RANSAC:
/// refinement starts from whichever pose has more inliers, so a good guess
/// survives a RANSAC failure; with `options.refine_guess` the guess refined on
/// its wider neighbourhood competes too, by inliers after refinement. Matches with a non-finite point or pixel are
/// ignored. Deterministic: OpenCV's RANSAC draws from its own fixed-seed
/// generator and the refinement is single-threaded.
PoseEstimate estimatePosePnp(const std::vector<Eigen::Vector3d>& points_world,
                             const std::vector<Eigen::Vector2d>& pixels, const PinholeCamera& camera,
                             const std::optional<Eigen::Isometry3d>& guess_wc, const PnpOptions& options = {});

/// Minimises sum huber(|project(T_cw X) - x|) over the pose, for the matches
/// listed in `use`; huber_px = infinity gives plain least squares. Matches
/// behind the initial camera are left out; with fewer than 3 left, or when the
/// solver fails, the initial pose is returned. Throws std::invalid_argument
/// for mismatched sizes, an index out of range, a non-finite used value,
/// invalid intrinsics, huber_px <= 0 or max_iterations < 0.
Eigen::Isometry3d refinePoseHuber(const std::vector<Eigen::Vector3d>& points_world,
                                  const std::vector<Eigen::Vector2d>& pixels, const std::vector<int>& use,
                                  const PinholeCamera& camera, const Eigen::Isometry3d& initial_wc, double huber_px,
                                  int max_iterations);

/// Depth measured at each match (metres, 0 = none) and its noise model: with
/// them, refinement also fits each point's depth, whitened by the sensor's
/// sigma, as RGB-D bundle adjustment does (reprojection alone constrains
/// motion along the optical axis poorly).
struct DepthMeasurements {
  const std::vector<double>& depths;
  DepthNoiseModel noise;
};
Eigen::Isometry3d refinePoseHuber(const std::vector<Eigen::Vector3d>& points_world,
                                  const std::vector<Eigen::Vector2d>& pixels, const std::vector<int>& use,
                                  const PinholeCamera& camera, const Eigen::Isometry3d& initial_wc, double huber_px,
                                  int max_iterations, const DepthMeasurements& depth);

struct RelativeMotion {
  bool ok = false;
  std::string failure;
  Eigen::Isometry3d pose_2_in_1 = Eigen::Isometry3d::Identity();  // translation of unit norm
  std::vector<int> inliers;  // consistent with the model and in front of both cameras
  bool used_homography = false;
  /// Median angle between the two viewing rays of the inliers: below about a
  /// degree the translation direction is poorly determined (the rotation is not).
  double median_parallax_deg = 0.0;
};

struct RelativeMotionOptions {
  /// Noise per pixel coordinate, in both images. Sets the RANSAC thresholds
  /// (95 % chi-square bounds) and the scale of the model scores. Err on the
  /// high side: a plane's R_H sits near 0.45 when this equals the true noise
  /// (with 1 px noise, 29 of 40 synthetic planes kept the homography at
  /// pixel_sigma = 1, all 40 at 1.5) and nears 0.5 when it exceeds it.
  double pixel_sigma = 1.5;
};

/// The motion of camera 2 relative to camera 1 (the pose of 2 in 1's frame)
/// from matched pixels alone; the scale is unknown, so the translation has
/// unit norm. Fits an essential matrix and a homography with RANSAC and keeps
/// the homography when R_H = S_H / (S_H + S_E) > 0.45 (ORB-SLAM's scores),
/// i.e. for planar or low-parallax scenes. The essential matrix's motion is
/// refined by Levenberg-Marquardt on the Sampson distances (Ceres, Huber),
/// re-selecting its inliers; the homography's decompositions are told apart
/// by triangulating the inliers (most points in front of both cameras).
/// Needs at least 8 finite matches.
RelativeMotion estimateRelativeMotion2d2d(const std::vector<Eigen::Vector2d>& pixels1,
                                          const std::vector<Eigen::Vector2d>& pixels2, const PinholeCamera& camera,
                                          const RelativeMotionOptions& options = {});

}  // namespace weighted_icp::frontend
