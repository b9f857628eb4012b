#include "weighted_icp/frontend/geometry/motion_model.h"

#include <stdexcept>

namespace weighted_icp::frontend {

void ConstantVelocityModel::update(const Eigen::Isometry3d& pose_wc) {
  if (!pose_wc.matrix().allFinite()) throw std::invalid_argument("ConstantVelocityModel: pose is not finite");
  previous_wc_ = latest_wc_;
  latest_wc_ = pose_wc;
}

std::optional<Eigen::Isometry3d> ConstantVelocityModel::predict() const {
  if (!previous_wc_ || !latest_wc_) return std::nullopt;
  const Eigen::Isometry3d last_motion = previous_wc_->inverse() * *latest_wc_;
  return *latest_wc_ * last_motion;
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
