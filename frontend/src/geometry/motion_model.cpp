#include "weighted_icp/frontend/geometry/motion_model.h"

#include <cmath>
#include <stdexcept>

#include "weighted_icp/core/skew.h"

namespace weighted_icp::frontend {

namespace {

/// SO(3)'s left Jacobian for the rotation vector `omega`: what maps a twist's translational part to the translation
/// of its exponential (exp of [omega, rho] translates by V(omega) * rho).
Eigen::Matrix3d leftJacobian(const Eigen::Vector3d& omega) {
  const double theta = omega.norm();
  const Eigen::Matrix3d K = skew(omega);
  if (theta < 1e-6) return Eigen::Matrix3d::Identity() + 0.5 * K + K * K / 6.0;  // Taylor: the terms' 0/0 limits
  const double theta2 = theta * theta;
  return Eigen::Matrix3d::Identity() + (1.0 - std::cos(theta)) / theta2 * K +
         (theta - std::sin(theta)) / (theta2 * theta) * K * K;
}

}  // namespace

Eigen::Isometry3d scaledMotion(const Eigen::Isometry3d& motion, double factor) {
  if (!std::isfinite(factor) || factor < 0.0) throw std::invalid_argument("scaledMotion: factor must be >= 0");
  if (factor == 1.0) return motion;  // exactly, without a round trip through the twist
  // exp(factor * log(motion)): the same twist held `factor` times as long.
  const Eigen::AngleAxisd rotation(motion.linear());
  const Eigen::Vector3d omega = rotation.angle() * rotation.axis();
  const Eigen::Vector3d rho = leftJacobian(omega).inverse() * motion.translation();
  Eigen::Isometry3d scaled = Eigen::Isometry3d::Identity();
  scaled.linear() = Eigen::AngleAxisd(rotation.angle() * factor, rotation.axis()).toRotationMatrix();
  scaled.translation() = leftJacobian(factor * omega) * (factor * rho);
  return scaled;
}

void ConstantVelocityModel::update(const Eigen::Isometry3d& pose_wc, double timestamp) {
  if (!pose_wc.matrix().allFinite()) throw std::invalid_argument("ConstantVelocityModel: pose is not finite");
  previous_wc_ = latest_wc_;
  previous_timestamp_ = latest_timestamp_;
  latest_wc_ = pose_wc;
  latest_timestamp_ = timestamp;
}

std::optional<Eigen::Isometry3d> ConstantVelocityModel::predict() const {
  if (!previous_wc_ || !latest_wc_) return std::nullopt;
  const Eigen::Isometry3d last_motion = previous_wc_->inverse() * *latest_wc_;
  return *latest_wc_ * last_motion;
}

std::optional<Eigen::Isometry3d> ConstantVelocityModel::predict(double timestamp, const FrameClock& clock) const {
  if (!previous_wc_ || !latest_wc_) return std::nullopt;
  const int spanned = clock.periodsBetween(previous_timestamp_, latest_timestamp_);
  const int ahead = clock.periodsBetween(latest_timestamp_, timestamp);
  const Eigen::Isometry3d last_motion = previous_wc_->inverse() * *latest_wc_;
  return *latest_wc_ * scaledMotion(last_motion, static_cast<double>(ahead) / spanned);
}

void ConstantVelocityModel::reset() {
  previous_wc_.reset();
  latest_wc_.reset();
}

void ConstantVelocityModel::applyCorrection(const Eigen::Isometry3d& delta_wc) {
  if (previous_wc_) previous_wc_ = delta_wc * *previous_wc_;
  if (latest_wc_) latest_wc_ = delta_wc * *latest_wc_;
}

}  // namespace weighted_icp::frontend
