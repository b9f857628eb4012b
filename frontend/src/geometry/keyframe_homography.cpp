// Plane fits of a keyframe and the keyframe-to-frame homography (the KD-tree paper's Eq. 3, 4 and 8).

#include "weighted_icp/frontend/geometry/keyframe_homography.h"

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

#include <Eigen/Eigenvalues>

namespace weighted_icp::frontend {
namespace {

/// Least-squares plane through points (smallest eigenvector of their scatter).
Plane fitLeastSquares(const std::vector<Eigen::Vector3d>& points, const std::vector<std::size_t>& members) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const std::size_t i : members) mean += points[i];
  mean /= static_cast<double>(members.size());
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const std::size_t i : members) scatter += (points[i] - mean) * (points[i] - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(scatter);
  Plane plane;
  plane.normal = solver.eigenvectors().col(0).normalized();
  plane.offset = -plane.normal.dot(mean);
  return plane;
}

std::vector<std::size_t> inliersOf(const Plane& plane, const std::vector<Eigen::Vector3d>& points,
                                   const std::vector<std::size_t>& candidates, double tolerance) {
  std::vector<std::size_t> inliers;
  for (const std::size_t i : candidates)
    if (std::abs(plane.normal.dot(points[i]) + plane.offset) <= tolerance) inliers.push_back(i);
  return inliers;
}

}  // namespace

PlaneSet fitPlanes(const std::vector<Eigen::Vector3d>& points, const PlaneFitOptions& options) {
  if (options.max_planes < 0 || options.min_inliers < 3 || !(options.inlier_m > 0.0) || options.iterations < 1)
    throw std::invalid_argument("fitPlanes: needs max_planes >= 0, min_inliers >= 3, inlier_m > 0 and iterations >= 1");
  PlaneSet set;
  set.plane_of_point.assign(points.size(), -1);
  std::vector<std::size_t> remaining;
  for (std::size_t i = 0; i < points.size(); ++i)
    if (points[i].allFinite()) remaining.push_back(i);
  std::mt19937_64 random(options.seed);
  while (static_cast<int>(set.planes.size()) < options.max_planes &&
         remaining.size() >= static_cast<std::size_t>(options.min_inliers)) {
    std::uniform_int_distribution<std::size_t> pick(0, remaining.size() - 1);
    std::vector<std::size_t> best;
    for (int it = 0; it < options.iterations; ++it) {
      const Eigen::Vector3d& a = points[remaining[pick(random)]];
      const Eigen::Vector3d& b = points[remaining[pick(random)]];
      const Eigen::Vector3d& c = points[remaining[pick(random)]];
      const Eigen::Vector3d normal = (b - a).cross(c - a);
      if (normal.norm() < 1e-9) continue;
      Plane candidate{normal.normalized(), 0.0};
      candidate.offset = -candidate.normal.dot(a);
      std::vector<std::size_t> inliers = inliersOf(candidate, points, remaining, options.inlier_m);
      if (inliers.size() > best.size()) best.swap(inliers);
    }
    if (best.size() < static_cast<std::size_t>(options.min_inliers)) break;
    const Plane refined = fitLeastSquares(points, best);
    best = inliersOf(refined, points, remaining, options.inlier_m);
    if (best.size() < static_cast<std::size_t>(options.min_inliers)) break;
    const int index = static_cast<int>(set.planes.size());
    set.planes.push_back(refined);
    std::vector<std::size_t> left;
    std::size_t next = 0;
    for (const std::size_t i : remaining) {
      if (next < best.size() && best[next] == i) {
        set.plane_of_point[i] = index;
        ++next;
      } else {
        left.push_back(i);
      }
    }
    remaining.swap(left);
  }
  return set;
}

Plane planeToWorld(const Plane& plane_camera, const Eigen::Isometry3d& pose_wc) {
  // X_c = R^T (X_w - t): n^T R^T X_w - n^T R^T t + d = 0.
  Plane world;
  world.normal = pose_wc.linear() * plane_camera.normal;
  world.offset = plane_camera.offset - world.normal.dot(pose_wc.translation());
  return world;
}

Eigen::Matrix3d keyframeToFrameHomography(const PinholeCamera& camera, const Eigen::Isometry3d& keyframe_wc,
                                          const Eigen::Isometry3d& frame_wc, const Plane& plane_world) {
  const Eigen::Isometry3d keyframe_cw = keyframe_wc.inverse(), frame_cw = frame_wc.inverse();
  const Eigen::Matrix3d rotation_k = keyframe_cw.linear(), rotation_j = frame_cw.linear();
  const Eigen::Vector3d t_k = keyframe_cw.translation(), t_j = frame_cw.translation();
  const Eigen::Matrix3d rotation = rotation_j * rotation_k.transpose();
  const Eigen::Vector3d translation = t_j - rotation * t_k;
  const Eigen::Vector3d normal_k = rotation_k * plane_world.normal;
  const double offset_k = plane_world.offset - plane_world.normal.dot(rotation_k.transpose() * t_k);
  const Eigen::Matrix3d k = camera.intrinsicMatrix();
  return k * (rotation - translation * normal_k.transpose() / offset_k) * k.inverse();
}

Eigen::Vector2d applyHomography(const Eigen::Matrix3d& homography, const Eigen::Vector2d& pixel) {
  const Eigen::Vector3d mapped = homography * pixel.homogeneous();
  if (!(std::abs(mapped.z()) > 1e-12)) return Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
  return mapped.hnormalized();
}

}  // namespace weighted_icp::frontend
