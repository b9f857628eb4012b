// Odometry edge information from tracking (see tracking_information.h): each keyframe's reprojection Hessian
// against the landmarks it observes, propagated to the relative pose of two consecutive keyframes.
#include "weighted_icp/mapping/tracking_information.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace weighted_icp::mapping {

namespace {

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

/// One observation as the Hessian needs it: the landmark in the keyframe's camera, its covariance there, the
/// reprojection residual.
struct Observation {
  Eigen::Vector3d in_camera;
  Eigen::Matrix3d covariance;
  Eigen::Vector2d residual;
};

/// The keyframe's observations whose landmark projects within inlier_px of the measured pixel.
std::vector<Observation> inlierObservations(const KeyframeSnapshot& map, const frontend::Keyframe& keyframe,
                                            const PinholeCamera& camera, double inlier_px) {
  const Eigen::Isometry3d world_to_camera = keyframe.pose_wc.inverse();
  std::vector<Observation> observations;
  for (const frontend::MapPointId id : keyframe.observed_points) {
    const auto point = map.points.find(id);
    if (point == map.points.end() || !point->second.position.allFinite()) continue;
    for (const frontend::MapPointObservation& o : point->second.observations) {
      if (o.keyframe != keyframe.id) continue;
      const Eigen::Vector3d c = world_to_camera * point->second.position;
      if (!(c.z() > 0.0)) break;
      const Eigen::Vector2d residual = camera.project(c) - o.pixel;
      if (!residual.allFinite() || residual.norm() > inlier_px) break;
      const Eigen::Matrix3d covariance =
          point->second.covariance.allFinite() ? point->second.covariance : Eigen::Matrix3d::Zero();
      observations.push_back(
          {c, world_to_camera.linear() * covariance * world_to_camera.linear().transpose(), residual});
      break;
    }
  }
  return observations;
}

}  // namespace

std::optional<Covariance6d> keyframePoseCovariance(const KeyframeSnapshot& map, frontend::KeyframeId keyframe,
                                                   const PinholeCamera& camera,
                                                   const TrackingInformationOptions& options) {
  const auto found = map.keyframes.find(keyframe);
  if (found == map.keyframes.end()) return std::nullopt;
  const std::vector<Observation> observations = inlierObservations(map, found->second, camera, options.inlier_px);
  if (observations.size() < std::max<std::size_t>(options.min_observations, 3)) return std::nullopt;
  double squared = 0.0;
  for (const Observation& o : observations) squared += o.residual.squaredNorm();
  const double sigma =
      std::max(options.min_pixel_sigma_px, std::sqrt(squared / (2.0 * static_cast<double>(observations.size()))));
  // Perturbation pose_wc * Exp(dt, dr): the landmark in the camera moves by dc = -dt + c x dr = [-I, [c]x].
  Eigen::Matrix<double, 6, 6> hessian = Eigen::Matrix<double, 6, 6>::Zero();
  for (const Observation& o : observations) {
    const Eigen::Vector3d& c = o.in_camera;
    Eigen::Matrix<double, 2, 3> projection;
    projection << camera.fx / c.z(), 0.0, -camera.fx * c.x() / (c.z() * c.z()), 0.0, camera.fy / c.z(),
        -camera.fy * c.y() / (c.z() * c.z());
    Eigen::Matrix<double, 3, 6> dc;
    dc.leftCols<3>() = -Eigen::Matrix3d::Identity();
    dc.rightCols<3>() = skew(c);
    const Eigen::Matrix<double, 2, 6> J = projection * dc;
    const Eigen::Matrix2d pixel_covariance =
        sigma * sigma * Eigen::Matrix2d::Identity() + projection * o.covariance * projection.transpose();
    hessian += J.transpose() * pixel_covariance.inverse() * J;
  }
  hessian = 0.5 * (hessian + hessian.transpose());
  const Eigen::LDLT<Eigen::Matrix<double, 6, 6>> ldlt(hessian);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0.0)) return std::nullopt;
  const Covariance6d covariance = ldlt.solve(Eigen::Matrix<double, 6, 6>::Identity());
  if (!covariance.allFinite()) return std::nullopt;
  return Covariance6d(0.5 * (covariance + covariance.transpose()));
}

Information6d trackedOdometryInformation(const Eigen::Isometry3d& a_wc, const Covariance6d& covariance_a,
                                         const Eigen::Isometry3d& b_wc, const Covariance6d& covariance_b,
                                         const TrackingInformationOptions& options) {
  // The edge's error: translation R_a^T (p_b - p_a) - t_ab, rotation on the right of R_ab. Moving a by Exp(da)
  // changes them by (-dt_a + [t_ab]x dr_a, -R_ab^T dr_a); moving b by Exp(db) by (R_ab dt_b, dr_b).
  const Eigen::Isometry3d b_in_a = a_wc.inverse() * b_wc;
  const Eigen::Matrix3d R = b_in_a.linear();
  Eigen::Matrix<double, 6, 6> J_a = Eigen::Matrix<double, 6, 6>::Zero(), J_b = Eigen::Matrix<double, 6, 6>::Zero();
  J_a.topLeftCorner<3, 3>() = -Eigen::Matrix3d::Identity();
  J_a.topRightCorner<3, 3>() = skew(b_in_a.translation());
  J_a.bottomRightCorner<3, 3>() = -R.transpose();
  J_b.topLeftCorner<3, 3>() = R;
  J_b.bottomRightCorner<3, 3>() = Eigen::Matrix3d::Identity();
  Covariance6d covariance =
      options.covariance_inflation * (J_a * covariance_a * J_a.transpose() + J_b * covariance_b * J_b.transpose());
  covariance.diagonal().head<3>().array() += options.translation_floor_m * options.translation_floor_m;
  covariance.diagonal().tail<3>().array() += options.rotation_floor_rad * options.rotation_floor_rad;
  covariance = 0.5 * (covariance + covariance.transpose());
  const Information6d information = covariance.ldlt().solve(Information6d::Identity());
  return 0.5 * (information + information.transpose());
}

}  // namespace weighted_icp::mapping
