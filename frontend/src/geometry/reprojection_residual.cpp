#include "weighted_icp/frontend/geometry/reprojection_residual.h"

namespace weighted_icp::frontend {

namespace {

/// d(R(q) x)/dq in ambient quaternion coordinates (x y z w). From
/// R(q) x = x + 2w (v × x) + 2 v × (v × x) with q = (v, w), valid on the unit
/// sphere, which is all the quaternion manifold's tangent directions see.
Eigen::Matrix<double, 3, 4> rotatedPointJacobian(const Eigen::Quaterniond& q, const Eigen::Vector3d& x) {
  const Eigen::Vector3d v = q.vec();
  const double w = q.w();
  Eigen::Matrix3d x_cross;
  x_cross << 0, -x.z(), x.y(), x.z(), 0, -x.x(), -x.y(), x.x(), 0;
  Eigen::Matrix<double, 3, 4> jacobian;
  jacobian.leftCols<3>() =
      -2.0 * w * x_cross + 2.0 * (v * x.transpose() + v.dot(x) * Eigen::Matrix3d::Identity() - 2.0 * x * v.transpose());
  jacobian.col(3) = 2.0 * v.cross(x);
  return jacobian;
}

/// Whitened residual rows of one observation: the reprojection (2 rows) and,
/// for kRows = 3, the depth. Jacobian pointers may be null (not wanted).
template <int kRows>
bool evaluateObservation(const double* pose, const Eigen::Vector3d& point_world, const PixelMeasurement& m,
                         double depth, double inverse_depth_sigma, double* residuals, double* jacobian_pose,
                         double* jacobian_point) {
  using Rows3 = Eigen::Matrix<double, kRows, 3, Eigen::RowMajor>;
  using Rows7 = Eigen::Matrix<double, kRows, 7, Eigen::RowMajor>;
  const Eigen::Map<const Eigen::Quaterniond> q(pose);
  const Eigen::Matrix3d rotation = q.toRotationMatrix();
  const Eigen::Vector3d p = rotation * point_world + Eigen::Map<const Eigen::Vector3d>(pose + 4);
  if (p.z() < kMinPointDepth) return false;
  const double inverse_z = 1.0 / p.z();
  residuals[0] = (m.fx * p.x() * inverse_z + m.cx - m.pixel.x()) * m.inverse_pixel_sigma;
  residuals[1] = (m.fy * p.y() * inverse_z + m.cy - m.pixel.y()) * m.inverse_pixel_sigma;
  if constexpr (kRows == 3) residuals[2] = (p.z() - depth) * inverse_depth_sigma;
  if (!jacobian_pose && !jacobian_point) return true;

  Rows3 d_residual_d_p;  // d residual / d X_c
  d_residual_d_p.template topRows<2>() << m.fx * inverse_z, 0, -m.fx * p.x() * inverse_z * inverse_z,  //
      0, m.fy * inverse_z, -m.fy * p.y() * inverse_z * inverse_z;
  d_residual_d_p.template topRows<2>() *= m.inverse_pixel_sigma;
  if constexpr (kRows == 3) d_residual_d_p.row(2) << 0, 0, inverse_depth_sigma;
  if (jacobian_pose) {
    Eigen::Map<Rows7> j{jacobian_pose};
    j.template leftCols<4>() = d_residual_d_p * rotatedPointJacobian(q, point_world);
    j.template rightCols<3>() = d_residual_d_p;
  }
  if (jacobian_point) Eigen::Map<Rows3>{jacobian_point} = d_residual_d_p * rotation;
  return true;
}

double* jacobianOrNull(double** jacobians, int block) { return jacobians ? jacobians[block] : nullptr; }

}  // namespace

PoseParameters PoseParameters::fromPoseWc(const Eigen::Isometry3d& pose_wc) {
  const Eigen::Isometry3d pose_cw = pose_wc.inverse();
  PoseParameters parameters;
  Eigen::Map<Eigen::Quaterniond>{parameters.data()} = Eigen::Quaterniond(pose_cw.linear()).normalized();
  Eigen::Map<Eigen::Vector3d>{parameters.data() + 4} = pose_cw.translation();
  return parameters;
}

Eigen::Isometry3d PoseParameters::poseWc() const {
  Eigen::Isometry3d pose_cw = Eigen::Isometry3d::Identity();
  pose_cw.linear() = Eigen::Map<const Eigen::Quaterniond>(data()).normalized().toRotationMatrix();
  pose_cw.translation() = Eigen::Map<const Eigen::Vector3d>(data() + 4);
  return pose_cw.inverse();
}

Eigen::Vector3d PoseParameters::toCamera(const Eigen::Vector3d& point_world) const {
  return Eigen::Map<const Eigen::Quaterniond>(data()) * point_world + Eigen::Map<const Eigen::Vector3d>(data() + 4);
}

PixelMeasurement::PixelMeasurement(const PinholeCamera& camera, const Eigen::Vector2d& pixel, double pixel_sigma)
    : fx(camera.fx),
      fy(camera.fy),
      cx(camera.cx),
      cy(camera.cy),
      pixel(pixel),
      inverse_pixel_sigma(1.0 / pixel_sigma) {}

ReprojectionResidual::ReprojectionResidual(const PinholeCamera& camera, const Eigen::Vector2d& pixel,
                                           double pixel_sigma)
    : measurement_(camera, pixel, pixel_sigma) {}

bool ReprojectionResidual::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  return evaluateObservation<2>(parameters[0], Eigen::Map<const Eigen::Vector3d>(parameters[1]), measurement_, 0.0, 0.0,
                                residuals, jacobianOrNull(jacobians, 0), jacobianOrNull(jacobians, 1));
}

RgbdResidual::RgbdResidual(const PinholeCamera& camera, const Eigen::Vector2d& pixel, double pixel_sigma, double depth,
                           double depth_sigma)
    : measurement_(camera, pixel, pixel_sigma), depth_(depth), inverse_depth_sigma_(1.0 / depth_sigma) {}

bool RgbdResidual::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  return evaluateObservation<3>(parameters[0], Eigen::Map<const Eigen::Vector3d>(parameters[1]), measurement_, depth_,
                                inverse_depth_sigma_, residuals, jacobianOrNull(jacobians, 0),
                                jacobianOrNull(jacobians, 1));
}

PoseOnlyReprojectionResidual::PoseOnlyReprojectionResidual(const PinholeCamera& camera,
                                                           const Eigen::Vector3d& point_world,
                                                           const Eigen::Vector2d& pixel, double pixel_sigma)
    : measurement_(camera, pixel, pixel_sigma), point_world_(point_world) {}

bool PoseOnlyReprojectionResidual::Evaluate(double const* const* parameters, double* residuals,
                                            double** jacobians) const {
  return evaluateObservation<2>(parameters[0], point_world_, measurement_, 0.0, 0.0, residuals,
                                jacobianOrNull(jacobians, 0), nullptr);
}

}  // namespace weighted_icp::frontend
