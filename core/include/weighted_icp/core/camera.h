#pragma once
// The RGB-D pinhole camera model every layer shares: intrinsics, lens
// distortion (OpenCV's k1 k2 p1 p2 k3) and the depth image scale, with the
// published TUM RGB-D calibrations. Reading and writing camera files is io's
// job (weighted_icp/io/camera.h).

#include <array>
#include <optional>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

namespace weighted_icp {

/// @brief The depth camera of a sensor whose depth images are not registered to its colour images (raw Kinect or
/// Astra streams): its pinhole intrinsics (depth images are taken as undistorted) and its pose in the colour
/// camera's frame.
struct DepthCamera {
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;
  /// @brief x_colour = R x_depth + t: the translation t (metres) and R as a rotation vector (radians).
  std::array<double, 3> translation_m{}, rotation_rad{};
  /// @brief The depth images' size in pixels when it is not the colour images' (an Azure Kinect's 640x576 depth
  /// beside 1280x720 colour); 0 x 0 (the default): the colour images' size.
  int width = 0, height = 0;

  /// @brief The depth camera's pose in the colour camera's frame (maps depth-camera coordinates to colour-camera
  /// coordinates).
  Eigen::Isometry3d depthInColor() const;
  /// @brief Its intrinsics for its image resampled by sx (columns) and sy (rows): old pixel u spans [u - 0.5, u + 0.5],
  /// which the new grid covers as [(u - 0.5) s, (u + 0.5) s], so f s and (c + 0.5) s - 0.5 (cv::resize's mapping).
  /// The pose and the image size (width, height) are left to the caller.
  /// @param sx new width / old
  /// @param sy new height / old
  DepthCamera resampled(double sx, double sy) const;
};

/// @brief A pinhole RGB-D camera: intrinsics, distortion and depth scale.
struct PinholeCamera {
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;
  std::array<double, 5> distortion{};  // k1 k2 p1 p2 k3
  int width = 640, height = 480;
  double depth_factor = 5000.0;  // depth image value per metre
  /// @brief Set when the depth images are not registered to the colour images: the front end then registers each
  /// one (frontend::registerDepthToColor). Unset: depth pixel (u, v) is colour pixel (u, v).
  std::optional<DepthCamera> unregistered_depth;

  /// @brief The size of the depth images the sensor delivers: the unregistered depth camera's own when it has one,
  /// else the colour images' (width x height).
  cv::Size depthImageSize() const;
  /// @brief The 3x3 intrinsic matrix as OpenCV takes it.
  cv::Matx33d cameraMatrix() const;
  /// @brief The same 3x3 intrinsic matrix K for Eigen arithmetic (homographies, fundamental matrices).
  Eigen::Matrix3d intrinsicMatrix() const;
  /// @brief The distortion coefficients as a 1x5 CV_64F row (k1 k2 p1 p2 k3).
  cv::Mat distortionCoefficients() const;
  /// @brief True when any distortion coefficient is non-zero.
  bool hasDistortion() const;

  /// @brief Pixel of a point in camera coordinates (z forward), without
  /// distortion; NaN for a point on or behind the image plane.
  /// @param point_camera the point in the camera frame, metres
  Eigen::Vector2d project(const Eigen::Vector3d& point_camera) const;
  /// @brief d(project)/d(point): the 2x3 Jacobian of the undistorted pixel with respect to the point in camera
  /// coordinates; the caller ensures the point is in front of the camera (z > 0).
  /// @param point_camera the point in the camera frame, metres
  Eigen::Matrix<double, 2, 3> projectionJacobian(const Eigen::Vector3d& point_camera) const;
  /// @brief Camera coordinates of an undistorted pixel at metric depth.
  /// @param u column, pixels
  /// @param v row, pixels
  /// @param depth along the optical axis, metres
  Eigen::Vector3d backProject(double u, double v, double depth) const;
  /// @brief True when the pixel lies within [0, width - 1] x [0, height - 1].
  /// @param pixel column and row
  bool inImage(const Eigen::Vector2d& pixel) const;
};

/// @brief The published calibration of TUM RGB-D freiburg 1, 2 or 3.
/// @param freiburg 1, 2 or 3; anything else throws std::invalid_argument
PinholeCamera tumCamera(int freiburg);

}  // namespace weighted_icp
