#pragma once
// Synthetic scenes for the geometry tests: a camera, points in view, noise.

#include <cmath>
#include <random>
#include <set>
#include <vector>

#include <Eigen/Geometry>

#include "weighted_icp/io/camera.h"

namespace weighted_icp::testing {

inline PinholeCamera syntheticCamera() {
  PinholeCamera camera;
  camera.fx = 525.0;
  camera.fy = 525.0;
  camera.cx = 319.5;
  camera.cy = 239.5;
  return camera;
}

inline double degToRad(double degrees) { return degrees * EIGEN_PI / 180.0; }

inline Eigen::Isometry3d makePose(const Eigen::Vector3d& axis_angle_deg, const Eigen::Vector3d& translation) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  const double angle = degToRad(axis_angle_deg.norm());
  if (angle > 0) pose.linear() = Eigen::AngleAxisd(angle, axis_angle_deg.normalized()).toRotationMatrix();
  pose.translation() = translation;
  return pose;
}

/// `pose` moved by a random rotation of `rotation_deg` and a random
/// translation of `translation_m` (fixed magnitudes, random directions).
inline Eigen::Isometry3d perturbPose(const Eigen::Isometry3d& pose, double translation_m, double rotation_deg,
                                     std::mt19937& rng) {
  std::normal_distribution<double> gauss(0.0, 1.0);
  const Eigen::Vector3d axis = Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized();
  const Eigen::Vector3d direction = Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized();
  return pose * makePose(rotation_deg * axis, translation_m * direction);
}

/// `n` world points seen by the camera at `pose_wc`: uniform pixels, depths uniform in [z_min, z_max].
inline std::vector<Eigen::Vector3d> pointsInView(const PinholeCamera& camera, const Eigen::Isometry3d& pose_wc, int n,
                                                 double z_min, double z_max, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(20.0, camera.width - 20.0), v(20.0, camera.height - 20.0), z(z_min, z_max);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < n; ++i) {
    const double pu = u(rng), pv = v(rng);
    points.push_back(pose_wc * camera.backProject(pu, pv, z(rng)));
  }
  return points;
}

inline Eigen::Vector2d projectWorld(const PinholeCamera& camera, const Eigen::Isometry3d& pose_wc,
                                    const Eigen::Vector3d& point_world) {
  return camera.project(pose_wc.inverse() * point_world);
}

inline Eigen::Vector2d gaussianPixel(double sigma, std::mt19937& rng) {
  std::normal_distribution<double> gauss(0.0, sigma);
  const double du = gauss(rng);
  return {du, gauss(rng)};
}

/// Matches of a camera at `truth_wc`: noisy pixels, and a fraction replaced by random pixels.
struct PnpScene {
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector2d> pixels;
  std::set<int> outliers;
};

inline PnpScene makePnpScene(const PinholeCamera& camera, const Eigen::Isometry3d& truth_wc, int n, double pixel_sigma,
                             double outlier_fraction, unsigned seed) {
  std::mt19937 rng(seed);
  PnpScene scene;
  scene.points = pointsInView(camera, truth_wc, n, 1.0, 5.0, rng);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  for (int i = 0; i < n; ++i) {
    scene.pixels.push_back(projectWorld(camera, truth_wc, scene.points[i]) + gaussianPixel(pixel_sigma, rng));
    if (i < static_cast<int>(outlier_fraction * n)) {
      scene.pixels.back() = {uniform(rng) * camera.width, uniform(rng) * camera.height};
      scene.outliers.insert(i);
    }
  }
  return scene;
}

/// Angle between two directions, in degrees.
inline double angleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / EIGEN_PI;
}

}  // namespace weighted_icp::testing
