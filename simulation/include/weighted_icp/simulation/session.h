#pragma once
// A synthetic RGB-D SLAM session with exact ground truth: landmarks on the
// surfaces of a room (walls, floor, a desk, boxes), a camera sweeping an arc
// while kept on the desk, noisy observations (occluded ones left out), and the
// map a drifting visual odometry builds from them. Alignment errors can then
// be measured against the true answer.
//
// Conventions: world z is up, the floor is z = 0 and the room is centred on
// x = y = 0. Cameras look along their +z axis with x right and y down (as
// OpenCV and TUM). Frame ids are 0 .. num_frames-1; frame 0 of the odometry
// is the true pose, so estimated and true maps share their origin.

#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "weighted_icp/core/camera.h"
#include "weighted_icp/registration/landmark_map.h"
#include "weighted_icp/simulation/rgbd_sequence.h"

namespace weighted_icp::simulation {

/// @brief The room, camera path, sensor and odometry of a session.
struct SyntheticSessionOptions {
  std::uint64_t seed = 1;
  std::size_t num_frames = 240;
  /// Landmarks placed on the surfaces; only those observed at least once are kept.
  std::size_t num_landmarks = 8000;

  /// Length (x), width (y) and height (z) of the room, metres. At least
  /// 3 x 3 x 2: the desk and boxes stand along the walls.
  Eigen::Vector3d room_size{6.0, 5.0, 3.0};

  /// The camera travels an arc of an ellipse around the room's centre whose
  /// semi-axes are this fraction of the room's half length and half width,
  /// from angle path_start_deg (0 is +x, 90 is +y) over path_arc_deg, one
  /// step per frame.
  double path_radius_fraction = 0.2;
  double path_start_deg = 210.0;
  double path_arc_deg = 120.0;
  /// Above the furniture (the desk with its box reaches 1.05 m).
  double camera_height = 1.4;
  /// Every frame looks at this point, as a hand-held camera kept on a scene
  /// of interest (TUM's fr1/desk). The default is above the desk's front
  /// edge in the default room, with the +y wall and its corners behind.
  Eigen::Vector3d look_at{-1.4, 1.6, 0.8};

  /// Must have no distortion: observations are ideal pinhole projections.
  PinholeCamera camera = syntheticRgbdCamera();
  double min_depth = 0.5;  // metres along the optical axis
  double max_depth = 4.0;
  /// A surface seen more obliquely than this (from its normal) yields no feature.
  double max_viewing_angle_deg = 70.0;
  /// Chance that a visible landmark is matched in a frame: real trackers miss
  /// some, so observation counts vary between landmarks.
  double detection_probability = 0.8;

  double pixel_noise_sigma = 0.5;  // pixels, both axes
  /// Depth noise sigma_z = coefficient * z^2 (structured-light RGB-D sensors).
  double depth_noise_coefficient = 0.0015;

  /// Odometry error per frame: a random walk, each frame's relative motion
  /// perturbed by these sigmas per axis (in the camera frame).
  double drift_rotation_sigma_deg = 0.03;
  double drift_translation_sigma = 0.001;  // metres
};

/// @brief A session's estimated map and its exact truth.
struct SyntheticSession {
  /// What a drifting visual odometry builds: odometry poses, and landmark
  /// positions back-projected from noisy pixels and depths with them (mean
  /// over observations), covariance propagated from the noise model.
  LandmarkMap estimated;
  /// The same frames and landmarks (ids, observations) with true poses and
  /// positions; covariances rotated with the true poses.
  LandmarkMap truth;
  /// Indexed by frame id; the poses of `truth.frames`.
  std::vector<Eigen::Isometry3d> true_camera_poses;
};

/// @brief Generates a session, deterministically for a seed.
/// @param options checked: std::invalid_argument names the first one out of
///        range; std::runtime_error when no landmark is observed
SyntheticSession generateSyntheticSession(const SyntheticSessionOptions& options);

}  // namespace weighted_icp::simulation
