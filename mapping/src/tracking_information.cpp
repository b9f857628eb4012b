// Odometry edge information from tracking (see tracking_information.h): each keyframe's reprojection Hessian
// against the landmarks it observes, propagated to the relative pose of two consecutive keyframes.
#include "weighted_icp/mapping/tracking_information.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "weighted_icp/core/skew.h"

namespace weighted_icp::mapping {

namespace {

/// One observation as the Hessian needs it: the landmark in the keyframe's camera, the reprojection residual,
/// the landmark's covariance in the world and the rotation that carries a world error into the camera.
struct Observation {
  Eigen::Vector3d in_camera;
  Eigen::Vector2d residual;
  frontend::MapPointId point = 0;
  Eigen::Matrix3d world_to_camera = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d world_covariance = Eigen::Matrix3d::Zero();
  /// The oldest keyframe other than this one that observes the landmark; none: the largest id.
  frontend::KeyframeId oldest_other_observer = std::numeric_limits<frontend::KeyframeId>::max();

  /// The landmark's covariance in the camera.
  Eigen::Matrix3d cameraCovariance() const { return world_to_camera * world_covariance * world_to_camera.transpose(); }
};

/// The keyframe's observations whose landmark projects within inlier_px of the measured pixel, by landmark id.
std::vector<Observation> inlierObservations(const KeyframeSnapshot& map, const frontend::Keyframe& keyframe,
                                            const PinholeCamera& camera, double inlier_px) {
  const Eigen::Isometry3d world_to_camera = keyframe.pose_wc.inverse();
  std::vector<frontend::MapPointId> ids = keyframe.observed_points;
  std::sort(ids.begin(), ids.end());
  std::vector<Observation> observations;
  for (const frontend::MapPointId id : ids) {
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
      observations.push_back({c, residual, id, world_to_camera.linear(), covariance});
      for (const frontend::MapPointObservation& other : point->second.observations)
        if (other.keyframe != keyframe.id)
          observations.back().oldest_other_observer =
              std::min(observations.back().oldest_other_observer, other.keyframe);
      break;
    }
  }
  return observations;
}

/// The pixel noise of a keyframe's inliers: their RMS per coordinate, at least the floor.
double pixelSigma(const std::vector<Observation>& observations, double min_sigma_px) {
  double squared = 0.0;
  for (const Observation& o : observations) squared += o.residual.squaredNorm();
  return std::max(min_sigma_px, std::sqrt(squared / (2.0 * static_cast<double>(observations.size()))));
}

/// d(pixel)/d(pose perturbation pose_wc * Exp(dt, dr)): the landmark in the camera moves by -dt + [c]x dr.
Eigen::Matrix<double, 2, 6> poseJacobian(const Eigen::Matrix<double, 2, 3>& projection, const Eigen::Vector3d& c) {
  Eigen::Matrix<double, 3, 6> dc;
  dc.leftCols<3>() = -Eigen::Matrix3d::Identity();
  dc.rightCols<3>() = skew(c);
  return projection * dc;
}

/// d(edge error)/d(perturbation of a) and d(edge error)/d(perturbation of b) for the edge a -> b.
std::pair<Eigen::Matrix<double, 6, 6>, Eigen::Matrix<double, 6, 6>> edgeJacobians(const Eigen::Isometry3d& a_wc,
                                                                                  const Eigen::Isometry3d& b_wc) {
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
  return {J_a, J_b};
}

/// Inflation and floors on a relative-pose covariance, then its inverse.
Information6d withInflationAndFloors(Covariance6d covariance, const TrackingInformationOptions& options) {
  covariance *= options.covariance_inflation;
  covariance.diagonal().head<3>().array() += options.translation_floor_m * options.translation_floor_m;
  covariance.diagonal().tail<3>().array() += options.rotation_floor_rad * options.rotation_floor_rad;
  covariance = 0.5 * (covariance + covariance.transpose());
  const Information6d information = covariance.ldlt().solve(Information6d::Identity());
  return 0.5 * (information + information.transpose());
}

/// True when a landmark only one keyframe of the pair sees holds that keyframe in the map: another keyframe older
/// than the newer of the two observes it, so its position was measured apart from the keyframe. One mapped from the
/// keyframe itself (or seen since only by later ones) holds it to its own measurement: counted with its map
/// covariance, it claimed a link as firm as tracking's wherever consecutive keyframes share few landmarks (fr3 there
/// and back made dark: a verified loop refused on two of six draws, 5.71 and 10.07 cm; docs/mapping.md).
bool heldApart(const Observation& alone, frontend::KeyframeId newer) { return alone.oldest_other_observer < newer; }

/// The information of two keyframes' poses (12 x 12, a's perturbation first) from the landmarks either sees:
/// both poses and every landmark are unknowns of one Gauss-Newton system, the landmarks held by their map
/// covariances as a prior, and the landmarks are eliminated (Schur complement). A landmark both keyframes see
/// then moves both alike, so its error cancels in their relative pose instead of being counted once per keyframe.
/// A landmark only one sees eliminates in closed form, its covariance joining the pixel noise as in
/// keyframePoseCovariance, when it is held apart from that keyframe (heldApart); otherwise it is left out.
/// Each list is sorted by landmark id (inlierObservations' order); `newer` is the newer keyframe's id.
Eigen::Matrix<double, 12, 12> twoPoseInformation(const std::vector<Observation>& seen_a,
                                                 const std::vector<Observation>& seen_b, const PinholeCamera& camera,
                                                 double min_pixel_sigma_px, frontend::KeyframeId newer) {
  const std::array<double, 2> weight = {1.0 / std::pow(pixelSigma(seen_a, min_pixel_sigma_px), 2),
                                        1.0 / std::pow(pixelSigma(seen_b, min_pixel_sigma_px), 2)};
  Eigen::Matrix<double, 12, 12> poses = Eigen::Matrix<double, 12, 12>::Zero();
  const auto alone = [&](int k, const Observation& o) {
    if (!heldApart(o, newer)) return;
    const Eigen::Matrix<double, 2, 3> projection = camera.projectionJacobian(o.in_camera);
    const Eigen::Matrix<double, 2, 6> J = poseJacobian(projection, o.in_camera);
    const Eigen::Matrix2d pixel_covariance =
        Eigen::Matrix2d::Identity() / weight[k] + projection * o.cameraCovariance() * projection.transpose();
    poses.block<6, 6>(6 * k, 6 * k) += J.transpose() * pixel_covariance.inverse() * J;
  };
  const auto shared = [&](const Observation& in_a, const Observation& in_b) {
    // A landmark without a covariance is taken as known to 0.1 mm, so that its prior stays invertible.
    Eigen::Matrix3d hessian =
        (in_a.world_covariance + 1e-8 * Eigen::Matrix3d::Identity()).ldlt().solve(Eigen::Matrix3d::Identity());
    Eigen::Matrix<double, 12, 3> coupling = Eigen::Matrix<double, 12, 3>::Zero();
    for (int k = 0; k < 2; ++k) {
      const Observation& o = k == 0 ? in_a : in_b;
      const Eigen::Matrix<double, 2, 3> projection = camera.projectionJacobian(o.in_camera);
      const Eigen::Matrix<double, 2, 6> J_pose = poseJacobian(projection, o.in_camera);
      const Eigen::Matrix<double, 2, 3> J_point = projection * o.world_to_camera;
      poses.block<6, 6>(6 * k, 6 * k) += weight[k] * J_pose.transpose() * J_pose;
      hessian += weight[k] * J_point.transpose() * J_point;
      coupling.middleRows<6>(6 * k) += weight[k] * J_pose.transpose() * J_point;
    }
    poses -= coupling * hessian.ldlt().solve(coupling.transpose());
  };
  // Merge the two lists by landmark.
  std::size_t i = 0, j = 0;
  while (i < seen_a.size() || j < seen_b.size()) {
    if (j == seen_b.size() || (i < seen_a.size() && seen_a[i].point < seen_b[j].point)) {
      alone(0, seen_a[i++]);
    } else if (i == seen_a.size() || seen_b[j].point < seen_a[i].point) {
      alone(1, seen_b[j++]);
    } else {
      shared(seen_a[i++], seen_b[j++]);
    }
  }
  return 0.5 * (poses + poses.transpose());
}

}  // namespace

std::optional<Covariance6d> keyframePoseCovariance(const KeyframeSnapshot& map, frontend::KeyframeId keyframe,
                                                   const PinholeCamera& camera,
                                                   const TrackingInformationOptions& options) {
  const auto found = map.keyframes.find(keyframe);
  if (found == map.keyframes.end()) return std::nullopt;
  const std::vector<Observation> observations = inlierObservations(map, found->second, camera, options.inlier_px);
  if (observations.size() < std::max<std::size_t>(options.min_observations, 3)) return std::nullopt;
  const double sigma = pixelSigma(observations, options.min_pixel_sigma_px);
  Eigen::Matrix<double, 6, 6> hessian = Eigen::Matrix<double, 6, 6>::Zero();
  for (const Observation& o : observations) {
    const Eigen::Matrix<double, 2, 3> projection = camera.projectionJacobian(o.in_camera);
    const Eigen::Matrix<double, 2, 6> J = poseJacobian(projection, o.in_camera);
    const Eigen::Matrix2d pixel_covariance =
        sigma * sigma * Eigen::Matrix2d::Identity() + projection * o.cameraCovariance() * projection.transpose();
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
  const auto [J_a, J_b] = edgeJacobians(a_wc, b_wc);
  return withInflationAndFloors(J_a * covariance_a * J_a.transpose() + J_b * covariance_b * J_b.transpose(), options);
}

namespace {

/// True when the two lists (sorted by landmark id) hold a landmark in common. Without one the two poses were never
/// measured against each other: each is held only by landmarks mapped from itself (a keyframe the dense odometry
/// posed maps its own points), and a covariance from them alone claimed a link as firm as tracking's, so the pose
/// graph refused loops that had to bend it (fr3 there and back made dark, draws 2 and 4: 5.54 -> 3.45 and
/// 6.46 -> 4.95 cm once they are admitted).
bool shareALandmark(const std::vector<Observation>& seen_a, const std::vector<Observation>& seen_b) {
  for (std::size_t i = 0, j = 0; i < seen_a.size() && j < seen_b.size();) {
    if (seen_a[i].point == seen_b[j].point) return true;
    if (seen_a[i].point < seen_b[j].point)
      ++i;
    else
      ++j;
  }
  return false;
}

/// The relative covariance a -> b from both keyframes' inlier observations (relativePoseCovariance's steps 2-3).
std::optional<Covariance6d> relativeFromObservations(const std::vector<Observation>& seen_a,
                                                     const std::vector<Observation>& seen_b,
                                                     const frontend::Keyframe& a, const frontend::Keyframe& b,
                                                     const PinholeCamera& camera,
                                                     const TrackingInformationOptions& options) {
  const std::size_t needed = std::max<std::size_t>(options.min_observations, 3);
  if (seen_a.size() < needed || seen_b.size() < needed || !shareALandmark(seen_a, seen_b)) return std::nullopt;
  const Eigen::Matrix<double, 12, 12> poses =
      twoPoseInformation(seen_a, seen_b, camera, options.min_pixel_sigma_px, std::max(a.id, b.id));
  const Eigen::LDLT<Eigen::Matrix<double, 12, 12>> ldlt(poses);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0.0)) return std::nullopt;
  const Eigen::Matrix<double, 12, 12> joint = ldlt.solve(Eigen::Matrix<double, 12, 12>::Identity());
  const auto [J_a, J_b] = edgeJacobians(a.pose_wc, b.pose_wc);
  Eigen::Matrix<double, 6, 12> J;
  J << J_a, J_b;
  const Covariance6d covariance = J * joint * J.transpose();
  if (!covariance.allFinite()) return std::nullopt;
  return Covariance6d(0.5 * (covariance + covariance.transpose()));
}

}  // namespace

std::optional<Covariance6d> relativePoseCovariance(const KeyframeSnapshot& map, frontend::KeyframeId a,
                                                   frontend::KeyframeId b, const PinholeCamera& camera,
                                                   const TrackingInformationOptions& options) {
  const auto found_a = map.keyframes.find(a), found_b = map.keyframes.find(b);
  if (found_a == map.keyframes.end() || found_b == map.keyframes.end() || a == b) return std::nullopt;
  return relativeFromObservations(inlierObservations(map, found_a->second, camera, options.inlier_px),
                                  inlierObservations(map, found_b->second, camera, options.inlier_px), found_a->second,
                                  found_b->second, camera, options);
}

std::vector<std::optional<Covariance6d>> odometryEdgeCovariances(const KeyframeSnapshot& map,
                                                                 const std::vector<frontend::KeyframeId>& keyframes,
                                                                 const PinholeCamera& camera,
                                                                 const TrackingInformationOptions& options) {
  std::vector<std::optional<Covariance6d>> covariances(keyframes.size());
  std::vector<Observation> previous;
  const frontend::Keyframe* previous_keyframe = nullptr;
  for (std::size_t i = 0; i < keyframes.size(); ++i) {
    const auto found = map.keyframes.find(keyframes[i]);
    if (found == map.keyframes.end()) {
      previous_keyframe = nullptr;
      continue;
    }
    std::vector<Observation> current = inlierObservations(map, found->second, camera, options.inlier_px);
    if (previous_keyframe && previous_keyframe->id != found->second.id)
      covariances[i] = relativeFromObservations(previous, current, *previous_keyframe, found->second, camera, options);
    previous = std::move(current);
    previous_keyframe = &found->second;
  }
  return covariances;
}

Information6d relativeOdometryInformation(const Covariance6d& relative_covariance,
                                          const TrackingInformationOptions& options) {
  return withInflationAndFloors(relative_covariance, options);
}

}  // namespace weighted_icp::mapping
