#pragma once
// The keyframe-to-frame homography of the KD-tree paper (Eq. 8): the planes
// of a keyframe, and where a plane's features appear in a later frame.

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "weighted_icp/core/camera.h"

namespace weighted_icp::frontend {

/// @brief A plane n^T X + d = 0 (n unit), the paper's gamma = [n^T, d]^T (its Eq. 3).
struct Plane {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double offset = 0.0;
};

/// @brief How planes are sought among a keyframe's points.
struct PlaneFitOptions {
  int max_planes = 3;               // sought one after another, each among the points the previous left
  int min_inliers = 30;             // a smaller plane is not kept
  double inlier_m = 0.02;           // point-to-plane distance
  int iterations = 100;             // RANSAC samples per plane
  std::uint64_t seed = 0x9e3779b9;  // RANSAC's fixed seed: the planes are reproducible
};

/// @brief Planes found among `points` and, per point, the plane it lies on (-1: none).
struct PlaneSet {
  std::vector<Plane> planes;
  std::vector<int> plane_of_point;
};

/// @brief Sequential RANSAC plane fits, each refined by least squares on its inliers.
/// @param points 3D points (non-finite ones are never inliers).
/// @param options see PlaneFitOptions; throws std::invalid_argument when out of range.
PlaneSet fitPlanes(const std::vector<Eigen::Vector3d>& points, const PlaneFitOptions& options = {});

/// @brief The homography H_{k->j} of the paper's Eq. 8, mapping keyframe pixels of points on `plane_world` to frame j.
///
/// Reading: Eq. 8 is Eq. 4, m_j = K (R - t n^T / d) K^-1 m_k, with the motion
/// from keyframe k to frame j (R = R_j R_k^T, t = t_j - R t_k) and the plane
/// n_L^T X + d_L = 0 given in the world and carried into keyframe k
/// (n = R_k n_L, d = d_L - n_L^T R_k^T t_k). The extracted text of Eq. 8 is
/// garbled in its signs; this is the form that maps points exactly.
/// @param camera intrinsics K.
/// @param keyframe_wc camera-to-world pose of keyframe k (R_k, t_k are its inverse).
/// @param frame_wc camera-to-world pose of frame j.
/// @param plane_world the plane in world coordinates.
Eigen::Matrix3d keyframeToFrameHomography(const PinholeCamera& camera, const Eigen::Isometry3d& keyframe_wc,
                                          const Eigen::Isometry3d& frame_wc, const Plane& plane_world);

/// @brief A plane given in camera coordinates, expressed in the world.
/// @param plane_camera the plane in the camera of pose `pose_wc`.
/// @param pose_wc camera-to-world pose.
Plane planeToWorld(const Plane& plane_camera, const Eigen::Isometry3d& pose_wc);

/// @brief H applied to a pixel; NaN when the point maps to infinity.
/// @param homography 3x3. @param pixel keyframe pixel.
Eigen::Vector2d applyHomography(const Eigen::Matrix3d& homography, const Eigen::Vector2d& pixel);

}  // namespace weighted_icp::frontend
