#pragma once
// RGB-D pinhole cameras: intrinsics, lens distortion (OpenCV's k1 k2 p1 p2 k3)
// and the depth image scale. Presets for the TUM RGB-D sensors, or a YAML file.

#include <array>
#include <string>

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace weighted_icp::io {

struct PinholeCamera {
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;
  std::array<double, 5> distortion{};  // k1 k2 p1 p2 k3
  int width = 640, height = 480;
  double depth_factor = 5000.0;  // depth image value per metre

  cv::Matx33d cameraMatrix() const;
  cv::Mat distortionCoefficients() const;  // 1x5 CV_64F
  bool hasDistortion() const;

  /// Pixel of a point in camera coordinates (z forward), without distortion.
  Eigen::Vector2d project(const Eigen::Vector3d& point_camera) const;
  /// Camera coordinates of an undistorted pixel at metric depth.
  Eigen::Vector3d backProject(double u, double v, double depth) const;
  bool inImage(const Eigen::Vector2d& pixel) const;
};

/// The published calibration of TUM RGB-D freiburg 1, 2 or 3; throws
/// std::invalid_argument for another number.
PinholeCamera tumCamera(int freiburg);

/// "fr1", "fr2", "fr3" or the path of an OpenCV FileStorage YAML with keys fx,
/// fy, cx, cy, k1, k2, p1, p2, k3, width, height, depth_factor. Throws
/// std::runtime_error naming the file and every missing or invalid key.
PinholeCamera loadCamera(const std::string& preset_or_path);
/// Writes the YAML form read by loadCamera (atomically).
void saveCamera(const PinholeCamera& camera, const std::string& path);

}  // namespace weighted_icp::io
