#include "weighted_icp/registration/rigid_motion.h"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace weighted_icp {

namespace {
double radians(double degrees) { return degrees * M_PI / 180.0; }
}  // namespace

Eigen::Isometry3d Displacement::toIsometry() const {
  Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
  motion.linear() = (Eigen::AngleAxisd(radians(yaw_deg), Eigen::Vector3d::UnitZ()) *
                     Eigen::AngleAxisd(radians(pitch_deg), Eigen::Vector3d::UnitY()) *
                     Eigen::AngleAxisd(radians(roll_deg), Eigen::Vector3d::UnitX()))
                        .toRotationMatrix();
  motion.translation() = Eigen::Vector3d(x, y, z);
  return motion;
}

Displacement Displacement::parse(const std::string& text) {
  std::istringstream in(text);
  std::vector<double> values;
  std::string token;
  while (in >> token) {
    std::size_t used = 0;
    double value = 0.0;
    try {
      value = std::stod(token, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != token.size() || !std::isfinite(value))
      throw std::invalid_argument("displacement \"" + text + "\": '" + token + "' is not a finite number");
    values.push_back(value);
  }
  if (values.size() != 6)
    throw std::invalid_argument("displacement \"" + text + "\" has " + std::to_string(values.size()) +
                                " numbers; expected 6: x y z roll pitch yaw (metres, degrees)");
  return {values[0], values[1], values[2], values[3], values[4], values[5]};
}

std::string Displacement::toString() const {
  std::ostringstream out;
  out << x << ' ' << y << ' ' << z << ' ' << roll_deg << ' ' << pitch_deg << ' ' << yaw_deg;
  return out.str();
}

double rotationErrorDeg(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& truth) {
  // Via the quaternion: precise for small angles, where acos((trace-1)/2) is not.
  const Eigen::Quaterniond delta(truth.linear().transpose() * estimate.linear());
  return Eigen::AngleAxisd(delta).angle() * 180.0 / M_PI;
}

Eigen::Matrix4d inverseRigid(const Eigen::Matrix4d& transformation) {
  return Eigen::Isometry3d(transformation).inverse().matrix();
}

double translationError(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& truth) {
  return (estimate.translation() - truth.translation()).norm();
}

}  // namespace weighted_icp
