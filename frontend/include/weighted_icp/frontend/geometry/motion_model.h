#pragma once
// Constant-velocity prediction of the next camera pose, the seed of PnP.

#include <optional>

#include <Eigen/Geometry>

namespace weighted_icp::frontend {

/// T_wc(k+1) = T_wc(k) * (T_wc(k-1)^-1 * T_wc(k)): the last relative motion,
/// expressed in the camera frame, repeated.
class ConstantVelocityModel {
 public:
  /// Records the newest pose; throws std::invalid_argument for a non-finite one.
  void update(const Eigen::Isometry3d& pose_wc);
  /// The next pose; empty until two poses have been recorded.
  std::optional<Eigen::Isometry3d> predict() const;
  /// Forgets the poses, e.g. after tracking was lost.
  void reset();
  /// Moves the recorded poses by a world-frame correction (new = delta_wc * old),
  /// as a loop closure moves the map: the velocity, relative, is unchanged.
  void applyCorrection(const Eigen::Isometry3d& delta_wc);

 private:
  std::optional<Eigen::Isometry3d> previous_wc_;
  std::optional<Eigen::Isometry3d> latest_wc_;
};

}  // namespace weighted_icp::frontend
