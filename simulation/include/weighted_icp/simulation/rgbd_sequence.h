#pragma once
// A synthetic RGB-D sequence with exact ground truth, for developing and
// testing the visual SLAM front end without external data: a hand-held-like
// camera moving through a textured room (walls, floor, ceiling, a desk,
// boxes), rendered by ray casting into colour and depth images as a
// Kinect-like sensor would record them.
//
// Conventions: world z is up, the floor is z = 0 and the room is centred on
// x = y = 0. Cameras look along their +z axis with x right and y down (as
// OpenCV and TUM). Everything is deterministic for a seed.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "weighted_icp/core/camera.h"
#include "weighted_icp/core/rgbd_frame.h"

namespace weighted_icp::simulation {

/// @brief The sequences' default camera: TUM freiburg 1's RGB intrinsics
/// without its lens distortion, 640 x 480, depth factor 5000.
PinholeCamera syntheticRgbdCamera();

/// @brief What to render: length, camera, scene variants and sensor model.
struct SyntheticRgbdOptions {
  /// Drives the textures, the camera path's phases, the moving object's
  /// texture and all noise. Options other than the seed do not change what
  /// the seed chose (e.g. turning the moving object on keeps the room).
  std::uint64_t seed = 1;
  std::size_t frames = 150;
  double fps = 30.0;  // timestamps are frame / fps seconds
  /// Must have no distortion: the renderer casts undistorted rays.
  PinholeCamera camera = syntheticRgbdCamera();

  /// Frames the camera takes to go once round its elliptic path (about 2.2 x 1.7 m) and come back to
  /// where it started: with frames > frames_per_loop the sequence revisits its beginning (a loop). The
  /// default, 800, is about 9 mm and 0.6 deg per frame; loop-closure tests use fewer for a short loop.
  double frames_per_loop = 800.0;
  /// Perceptual aliasing: every face of the room and of the furniture shows the same texture tile
  /// (kRepeatedTileMetres square, drawn from the seed) repeated, so distinct places look alike and only
  /// geometry tells them apart. Off: every face has its own texture.
  bool repeated_texture = false;
  /// A larger room: its floor plan (6 x 5 m), the furniture's places along the walls and the camera's ellipse are
  /// stretched by this factor (height, furniture sizes and textures stay), so the walls are farther, their depth
  /// noisier (it grows with the square of the distance) and more of them beyond the sensor's range: a hall rather
  /// than an office, where odometry drifts more. The path is longer by the same factor, so keep the motion per
  /// frame by raising frames_per_loop with it. 1: the default room.
  double room_scale = 1.0;

  /// A textured box carried across the view now and then, covering up to
  /// about a fifth of the image while it passes.
  bool moving_object = false;
  /// A dim, low-contrast, noisy image (gain, gamma, sensor noise) on which a
  /// plain corner detector struggles.
  bool dim_lighting = false;

  /// Kinect-like depth error: Gaussian noise of sigma_z = coefficient * z^2,
  /// then quantisation of the disparity to 1/8 pixel. Off: depth is exact up
  /// to the depth image's resolution (1 / camera.depth_factor).
  bool depth_noise = true;
  double depth_noise_coefficient = 0.0015;
  /// Kinect-like depth distortion, an error fixed for the sensor that no averaging removes: every stored depth
  /// is multiplied by 1 + depth_distortion * r^2, r the pixel's distance from the principal point over the
  /// focal length (0.58 in the corners of a 640 x 480 image at 525 px), so a surface reads farther (or nearer,
  /// negative) towards the image's edges. A structured-light sensor's depth has such a spatially varying
  /// systematic error of about a per cent; the tracker's covariances, which know only random noise, do not
  /// expect the steady drift it causes. Zero (the default): none.
  double depth_distortion = 0.0;
  /// Sensor limits, applied with or without noise: depth is 0 (invalid)
  /// outside [min_depth, max_depth] (metres along the optical axis) and where
  /// the ray meets the surface more than max_incidence_deg from its normal.
  double min_depth = 0.4;
  double max_depth = 4.5;
  double max_incidence_deg = 75.0;

  /// Calibration error, the drift of a real camera nobody calibrated: the images are rendered with `camera`,
  /// but trackerCamera() hands the tracker intrinsics that are off by this much, as a user who takes a
  /// datasheet's or a driver's default intrinsics has (TUM freiburg 1 against the Kinect default 525 / 319.5 /
  /// 239.5: focal lengths 1.5 % too long, cy 16 px off). Every 3D point the tracker back-projects is then
  /// stretched sideways and every bearing bent, so the odometry drifts steadily with the motion, more on turns,
  /// and no amount of averaging removes it. focal_length_error is relative (0.02: fx and fy believed 2 %
  /// longer), the offsets in pixels. Zero (the default): the tracker gets `camera` itself.
  double focal_length_error = 0.0;
  double principal_point_error_x_px = 0.0;
  double principal_point_error_y_px = 0.0;
};

/// @brief An axis-aligned box turned by `yaw` about the vertical axis through its centre.
struct SceneBox {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Vector3d size = Eigen::Vector3d::Ones();  // metres along its own x, y, z
  double yaw = 0.0;                                // radians
};

/// @brief One rendered frame with its true pose.
struct SyntheticRgbdFrame {
  /// What a sensor gives: timestamp, colour (CV_8UC3, BGR) and metric depth
  /// (CV_32F; the 16-bit image the sensor model quantises to, divided by
  /// camera.depth_factor, so core's depthToRaw gives it back exactly).
  RgbdFrame rgbd;
  Eigen::Isometry3d camera_to_world = Eigen::Isometry3d::Identity();
  cv::Mat moving_object_mask;  // CV_8UC1, 255 where the moving object is seen
};

/// @brief The sequence: a scene drawn once from the seed, frames rendered on demand.
class SyntheticRgbdSequence {
 public:
  /// @brief Draws the scene's textures (some 0.3 s of CPU).
  /// @param options checked: std::invalid_argument names the first one out of range
  explicit SyntheticRgbdSequence(const SyntheticRgbdOptions& options);
  ~SyntheticRgbdSequence();
  SyntheticRgbdSequence(SyntheticRgbdSequence&&) noexcept;
  SyntheticRgbdSequence& operator=(SyntheticRgbdSequence&&) noexcept;

  /// @brief The number of frames (options().frames).
  std::size_t size() const;
  /// @brief The options it was made with.
  const SyntheticRgbdOptions& options() const;
  /// @brief The intrinsics to give the tracker: options().camera with the calibration error applied (fx, fy
  /// times 1 + focal_length_error, cx, cy moved by the principal-point errors); options().camera itself when
  /// they are zero. Ground truth (cameraToWorld) is unaffected: it is where the camera really was.
  PinholeCamera trackerCamera() const;

  /// @brief Renders frame i.
  /// @param i 0 <= i < size(), else std::out_of_range
  SyntheticRgbdFrame frame(std::size_t i) const;
  /// @brief The true camera-to-world pose of frame i, without rendering.
  Eigen::Isometry3d cameraToWorld(std::size_t i) const;
  /// @brief The timestamp of frame i: i / fps seconds.
  double timestamp(std::size_t i) const;

  /// @brief The room's size (room_scale applied): it spans [-x/2, x/2] x [-y/2, y/2] x [0, z].
  Eigen::Vector3d roomSize() const;
  /// @brief The furniture standing in the room.
  const std::vector<SceneBox>& furniture() const;
  /// @brief The moving object in frame i: one more box, when on and present.
  std::optional<SceneBox> movingObject(std::size_t i) const;

 private:
  struct Scene;
  SyntheticRgbdOptions options_;
  std::unique_ptr<const Scene> scene_;
};

}  // namespace weighted_icp::simulation
