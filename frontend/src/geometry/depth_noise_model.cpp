#include "weighted_icp/frontend/geometry/depth_noise_model.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Cholesky>

#include "input_checks.h"

namespace weighted_icp::frontend {

double DepthNoiseModel::sigmaDepth(double z) const { return depth_sigma_coefficient * z * z; }

Eigen::Matrix3d pointCovarianceCamera(const PinholeCamera& camera, double u, double v, double z,
                                      const DepthNoiseModel& noise) {
  if (const auto problem = detail::cameraProblem(camera)) throw std::invalid_argument(*problem);
  if (!(std::isfinite(z) && z > 0))
    throw std::invalid_argument("pointCovarianceCamera: depth must be positive, got " + std::to_string(z));
  if (!(std::isfinite(u) && std::isfinite(v)))
    throw std::invalid_argument("pointCovarianceCamera: pixel is not finite");
  if (!(noise.pixel_sigma > 0 && noise.depth_sigma_coefficient > 0 && std::isfinite(noise.pixel_sigma) &&
        std::isfinite(noise.depth_sigma_coefficient)))
    throw std::invalid_argument("pointCovarianceCamera: noise sigmas must be positive and finite");

  // X = (u - cx) z / fx, Y = (v - cy) z / fy, Z = z.
  Eigen::Matrix3d jacobian;
  jacobian << z / camera.fx, 0, (u - camera.cx) / camera.fx,  //
      0, z / camera.fy, (v - camera.cy) / camera.fy,          //
      0, 0, 1;
  const double pixel_variance = noise.pixel_sigma * noise.pixel_sigma;
  const double depth_sigma = noise.sigmaDepth(z);
  const Eigen::Vector3d variances(pixel_variance, pixel_variance, depth_sigma * depth_sigma);
  return jacobian * variances.asDiagonal() * jacobian.transpose();
}

FusedPoint fusePointEstimates(const std::vector<Eigen::Vector3d>& positions,
                              const std::vector<Eigen::Matrix3d>& covariances) {
  if (positions.empty()) throw std::invalid_argument("fusePointEstimates: no estimate");
  if (positions.size() != covariances.size())
    throw std::invalid_argument("fusePointEstimates: " + std::to_string(positions.size()) + " positions but " +
                                std::to_string(covariances.size()) + " covariances");
  Eigen::Matrix3d information = Eigen::Matrix3d::Zero();
  Eigen::Vector3d information_vector = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < positions.size(); ++i) {
    const Eigen::Matrix3d& covariance = covariances[i];
    if (!positions[i].allFinite() || !covariance.allFinite())
      throw std::invalid_argument("fusePointEstimates: estimate " + std::to_string(i) + " is not finite");
    const Eigen::LLT<Eigen::Matrix3d> cholesky(covariance);
    if (!covariance.isApprox(covariance.transpose(), 1e-9) || cholesky.info() != Eigen::Success)
      throw std::invalid_argument("fusePointEstimates: covariance " + std::to_string(i) +
                                  " is not symmetric positive definite");
    const Eigen::Matrix3d inverse = cholesky.solve(Eigen::Matrix3d::Identity());
    information += inverse;
    information_vector += inverse * positions[i];
  }
  FusedPoint fused;
  fused.covariance = information.llt().solve(Eigen::Matrix3d::Identity());
  fused.covariance = 0.5 * (fused.covariance + fused.covariance.transpose());
  fused.position = fused.covariance * information_vector;
  return fused;
}

}  // namespace weighted_icp::frontend
