#pragma once
// The one box and ray model of both simulators: boxes turned about the
// vertical, the slab test for rays and segments against them, and the pixels
// through which a camera can see one. The RGB-D sequence renders its room and
// furniture with it; the session tests landmark occlusion and cover with it.
// Private to the simulation library.

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "weighted_icp/core/camera.h"

namespace weighted_icp::simulation {

/// @brief Where a ray meets a face of a box.
struct FaceHit {
  double t = std::numeric_limits<double>::infinity();  ///< ray parameter: origin + t * direction
  int axis = 0;                                        ///< the face's normal axis, in the box's frame
  bool positive_side = false;                          ///< the face on the box's + side of `axis`
};

/// @brief The part of a ray inside a box, from the slab test.
struct SlabSpan {
  double t_near = 0.0, t_far = 0.0;  ///< ray parameters where it enters and leaves (t_near >= 0)
  int near_axis = -1;                ///< the axis of the face it enters through; -1 when it starts inside
};

/// @brief A box [lower, upper] in its own frame, which is the world frame
/// turned by `yaw` about the vertical axis through `origin`. Directions and
/// points given to the queries below are in the box's frame (toBox, pointInBox)
/// unless named world.
class RayBox {
 public:
  /// @brief A box of `size` centred on `center` (its frame's origin), turned by `yaw` radians.
  static RayBox centred(const Eigen::Vector3d& center, const Eigen::Vector3d& size, double yaw) {
    const Eigen::Vector3d half_size = size / 2.0;
    return RayBox(center, -half_size, half_size, yaw);
  }
  /// @brief An axis-aligned box with these world corners: its frame is the
  /// world's, so the corners are exactly its bounds.
  static RayBox fromCorners(const Eigen::Vector3d& min, const Eigen::Vector3d& max) {
    return RayBox(Eigen::Vector3d::Zero(), min, max, 0.0);
  }

  const Eigen::Vector3d& origin() const { return origin_; }
  const Eigen::Vector3d& lower() const { return lower_; }
  const Eigen::Vector3d& upper() const { return upper_; }

  /// @brief A world direction in the box's frame.
  Eigen::Vector3d toBox(const Eigen::Vector3d& world) const {
    return {cos_yaw_ * world.x() + sin_yaw_ * world.y(), -sin_yaw_ * world.x() + cos_yaw_ * world.y(), world.z()};
  }
  /// @brief A direction in the box's frame in the world.
  Eigen::Vector3d toWorld(const Eigen::Vector3d& local) const {
    return {cos_yaw_ * local.x() - sin_yaw_ * local.y(), sin_yaw_ * local.x() + cos_yaw_ * local.y(), local.z()};
  }
  /// @brief A world point in the box's frame.
  Eigen::Vector3d pointInBox(const Eigen::Vector3d& world_point) const { return toBox(world_point - origin_); }

  /// @brief Whether the world point is in the box or on its surface.
  bool contains(const Eigen::Vector3d& world_point) const {
    const Eigen::Vector3d local = pointInBox(world_point);
    return (local.array() >= lower_.array()).all() && (local.array() <= upper_.array()).all();
  }

  /// @brief Slab test: the part of the ray o + t d, t in [0, t_max], inside the box, if any.
  /// @param o the ray's origin, in the box's frame
  /// @param d the ray's direction, in the box's frame
  std::optional<SlabSpan> span(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_max) const {
    SlabSpan span{0.0, t_max, -1};
    for (int axis = 0; axis < 3; ++axis) {
      if (d[axis] == 0.0) {
        if (o[axis] < lower_[axis] || o[axis] > upper_[axis]) return std::nullopt;
        continue;
      }
      const double inverse = 1.0 / d[axis];
      double t1 = (lower_[axis] - o[axis]) * inverse, t2 = (upper_[axis] - o[axis]) * inverse;
      if (t1 > t2) std::swap(t1, t2);
      if (t1 > span.t_near) span.t_near = t1, span.near_axis = axis;
      span.t_far = std::min(span.t_far, t2);
      if (span.t_near > span.t_far) return std::nullopt;
    }
    return span;
  }

  /// @brief From outside: replaces `nearest` by the face the ray o + t d enters
  /// through, if it is nearer. A ray from inside enters nothing.
  /// @return whether `nearest` was replaced
  bool enter(const Eigen::Vector3d& o, const Eigen::Vector3d& d, FaceHit& nearest) const {
    const std::optional<SlabSpan> inside = span(o, d, nearest.t);
    if (!inside || inside->near_axis < 0 || inside->t_near >= nearest.t) return false;
    nearest = {inside->t_near, inside->near_axis, d[inside->near_axis] < 0.0};
    return true;
  }

  /// @brief From inside (a room): replaces `nearest` by the face the ray o + t d
  /// leaves through, if it is nearer.
  void leave(const Eigen::Vector3d& o, const Eigen::Vector3d& d, FaceHit& nearest) const {
    for (int axis = 0; axis < 3; ++axis) {
      if (d[axis] == 0.0) continue;
      const bool positive = d[axis] > 0.0;
      const double t = ((positive ? upper_[axis] : lower_[axis]) - o[axis]) / d[axis];
      if (t < nearest.t) nearest = {t, axis, positive};
    }
  }

  /// @brief Whether the world segment from `from` to just before `to` passes
  /// through the box: `to` may lie on the box's own face.
  bool blocksSegment(const Eigen::Vector3d& from, const Eigen::Vector3d& to) const {
    return span(pointInBox(from), toBox(to - from), 1.0 - 1e-9).has_value();
  }

 private:
  RayBox(const Eigen::Vector3d& origin, const Eigen::Vector3d& lower, const Eigen::Vector3d& upper, double yaw)
      : origin_(origin), lower_(lower), upper_(upper), cos_yaw_(std::cos(yaw)), sin_yaw_(std::sin(yaw)) {}

  Eigen::Vector3d origin_, lower_, upper_;
  double cos_yaw_, sin_yaw_;
};

/// @brief The pixels whose rays can meet `box` (its corners' projected bounding
/// rectangle with a pixel's margin, within the image): all of the image when a
/// corner is behind the camera, none when all are.
/// @param camera_to_world the camera's pose
/// @param camera pinhole model without distortion
cv::Rect pixelBounds(const RayBox& box, const Eigen::Isometry3d& camera_to_world, const PinholeCamera& camera);

}  // namespace weighted_icp::simulation
