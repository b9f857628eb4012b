// The pinhole camera model and the TUM RGB-D calibrations.
#include "weighted_icp/core/camera.h"

#include <limits>
#include <stdexcept>
#include <string>

namespace weighted_icp {

Eigen::Isometry3d DepthCamera::depthInColor() const {
  const Eigen::Vector3d rotation(rotation_rad[0], rotation_rad[1], rotation_rad[2]);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  if (rotation.norm() > 0.0)
    pose.linear() = Eigen::AngleAxisd(rotation.norm(), rotation.normalized()).toRotationMatrix();
  pose.translation() = Eigen::Vector3d(translation_m[0], translation_m[1], translation_m[2]);
  return pose;
}

DepthCamera DepthCamera::resampled(double sx, double sy) const {
  DepthCamera result = *this;
  result.fx *= sx;
  result.fy *= sy;
  result.cx = (cx + 0.5) * sx - 0.5;
  result.cy = (cy + 0.5) * sy - 0.5;
  return result;
}

cv::Size PinholeCamera::depthImageSize() const {
  if (unregistered_depth && unregistered_depth->width > 0 && unregistered_depth->height > 0)
    return {unregistered_depth->width, unregistered_depth->height};
  return {width, height};
}

cv::Matx33d PinholeCamera::cameraMatrix() const { return {fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0}; }

Eigen::Matrix3d PinholeCamera::intrinsicMatrix() const {
  Eigen::Matrix3d k;
  k << fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0;
  return k;
}

cv::Mat PinholeCamera::distortionCoefficients() const {
  cv::Mat coefficients(1, 5, CV_64F);
  for (int i = 0; i < 5; ++i) coefficients.at<double>(i) = distortion[static_cast<std::size_t>(i)];
  return coefficients;
}

bool PinholeCamera::hasDistortion() const {
  for (const double k : distortion)
    if (k != 0.0) return true;
  return false;
}

Eigen::Vector2d PinholeCamera::project(const Eigen::Vector3d& point_camera) const {
  // A point on or behind the image plane has no pixel; NaN makes inImage() false.
  if (!(point_camera.z() > 0.0)) return Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
  return {fx * point_camera.x() / point_camera.z() + cx, fy * point_camera.y() / point_camera.z() + cy};
}

Eigen::Matrix<double, 2, 3> PinholeCamera::projectionJacobian(const Eigen::Vector3d& point_camera) const {
  const double z = point_camera.z();
  Eigen::Matrix<double, 2, 3> jacobian;
  jacobian << fx / z, 0.0, -fx * point_camera.x() / (z * z), 0.0, fy / z, -fy * point_camera.y() / (z * z);
  return jacobian;
}

Eigen::Vector3d PinholeCamera::backProject(double u, double v, double depth) const {
  return {(u - cx) / fx * depth, (v - cy) / fy * depth, depth};
}

bool PinholeCamera::inImage(const Eigen::Vector2d& pixel) const {
  // Pixel centres are at integer coordinates: inside [0, size - 1] both the
  // rounded pixel and the bilinear neighbours exist.
  return pixel.x() >= 0.0 && pixel.y() >= 0.0 && pixel.x() <= width - 1 && pixel.y() <= height - 1;
}

PinholeCamera tumCamera(int freiburg) {
  PinholeCamera camera;
  switch (freiburg) {
    case 1:
      camera.fx = 517.306408, camera.fy = 516.469215, camera.cx = 318.643040, camera.cy = 255.313989;
      camera.distortion = {0.262383, -0.953104, -0.005358, 0.002628, 1.163314};
      break;
    case 2:
      camera.fx = 520.908620, camera.fy = 521.007327, camera.cx = 325.141442, camera.cy = 249.701764;
      camera.distortion = {0.231222, -0.784899, -0.003257, -0.000105, 0.917205};
      break;
    case 3: camera.fx = 535.4, camera.fy = 539.2, camera.cx = 320.1, camera.cy = 247.6; break;
    default:
      throw std::invalid_argument("no TUM RGB-D camera freiburg " + std::to_string(freiburg) + " (expected 1, 2 or 3)");
  }
  return camera;
}

}  // namespace weighted_icp
