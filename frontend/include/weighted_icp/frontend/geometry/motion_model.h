#pragma once
// Constant-velocity prediction of the next camera pose, the seed of PnP: per frame period, so that a dropped frame
// (a doubled interval) is predicted twice as far.

#include <limits>
#include <optional>

#include <Eigen/Geometry>

#include "weighted_icp/frontend/geometry/frame_clock.h"

namespace weighted_icp::frontend {

/// @brief The motion `factor` times as long at the same twist (exp(factor * log(motion)) on SE(3)): for a whole
/// factor n, the motion composed n times; for 1/2, the motion that composed twice gives it back.
/// @param motion a rigid motion
/// @param factor >= 0
Eigen::Isometry3d scaledMotion(const Eigen::Isometry3d& motion, double factor);

/// T_wc(k+1) = T_wc(k) * (T_wc(k-1)^-1 * T_wc(k)): the last relative motion,
/// expressed in the camera frame, repeated; with timestamps and a FrameClock,
/// repeated once per frame period elapsed, per period it spanned.
class ConstantVelocityModel {
 public:
  /// @brief Records the newest pose; throws std::invalid_argument for a non-finite one.
  /// @param pose_wc camera to world
  /// @param timestamp seconds; without one, predict(timestamp, clock) counts one period per pose
  void update(const Eigen::Isometry3d& pose_wc, double timestamp = std::numeric_limits<double>::quiet_NaN());
  /// @brief The pose one more last motion on; empty until two poses have been recorded.
  std::optional<Eigen::Isometry3d> predict() const;
  /// @brief The pose at `timestamp`: the last motion, per frame period it spanned, once per period since the
  /// newest pose (as the clock counts them); empty until two poses have been recorded.
  /// @param timestamp seconds
  /// @param clock the sensor's frame period
  std::optional<Eigen::Isometry3d> predict(double timestamp, const FrameClock& clock) const;
  /// @brief Forgets the poses, e.g. after tracking was lost.
  void reset();
  /// @brief Moves the recorded poses by a world-frame correction (new = delta_wc * old),
  /// as a loop closure moves the map: the velocity, relative, is unchanged.
  void applyCorrection(const Eigen::Isometry3d& delta_wc);

 private:
  std::optional<Eigen::Isometry3d> previous_wc_;
  std::optional<Eigen::Isometry3d> latest_wc_;
  double previous_timestamp_ = std::numeric_limits<double>::quiet_NaN();
  double latest_timestamp_ = std::numeric_limits<double>::quiet_NaN();
};

}  // namespace weighted_icp::frontend
