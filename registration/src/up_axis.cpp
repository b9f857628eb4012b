// The up axis of a map from its cameras' image rows, and the axes two maps are levelled by.
#include "weighted_icp/registration/up_axis.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Eigenvalues>

#include "weighted_icp/registration/global_alignment.h"

namespace weighted_icp {

UpAxisEstimate estimateUpAxis(const std::map<FrameId, Eigen::Isometry3d>& camera_poses, double min_heading_spread) {
  if (!(min_heading_spread >= 0.0 && min_heading_spread <= 0.5))
    throw std::invalid_argument("estimateUpAxis: min_heading_spread must be in [0, 0.5]");
  UpAxisEstimate estimate;
  Eigen::Matrix3d rows = Eigen::Matrix3d::Zero();
  Eigen::Vector3d down = Eigen::Vector3d::Zero(), right = Eigen::Vector3d::Zero();
  for (const auto& [id, pose] : camera_poses) {
    const Eigen::Matrix3d r = pose.linear();
    if (!r.allFinite()) continue;
    rows += r.col(0) * r.col(0).transpose();
    down += r.col(1);
    right += r.col(0);
    ++estimate.cameras;
  }
  if (estimate.cameras == 0) return estimate;
  rows /= static_cast<double>(estimate.cameras);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(rows);
  const Eigen::Vector3d spread = solver.eigenvalues();  // ascending
  estimate.rows = solver.eigenvectors().col(2);
  if (estimate.rows.dot(right) < 0.0) estimate.rows = -estimate.rows;  // along the cameras' x: a pitch has one sign
  estimate.heading_spread = spread(1);
  Eigen::Vector3d axis;
  estimate.from_rows = spread(1) >= min_heading_spread;
  if (estimate.from_rows) {
    axis = solver.eigenvectors().col(0);
  } else {
    // One heading: the rows fix only the plane perpendicular to them; the cameras' mean up direction in it.
    const Eigen::Vector3d along = solver.eigenvectors().col(2);
    axis = -down - along * along.dot(-down);
    if (!(axis.norm() > 1e-9)) axis = solver.eigenvectors().col(0);
  }
  axis.normalize();
  if (axis.dot(-down) < 0.0) axis = -axis;  // cameras upright: their y axes point down
  estimate.axis = axis;
  double tilt = 0.0;
  for (const auto& [id, pose] : camera_poses) {
    const double sine = pose.linear().col(0).dot(axis);
    if (std::isfinite(sine)) tilt += sine * sine;
  }
  estimate.row_tilt_deg =
      std::asin(std::min(1.0, std::sqrt(tilt / static_cast<double>(estimate.cameras)))) * 180.0 / M_PI;
  return estimate;
}

std::vector<Eigen::Vector3d> pitchedUpAxes(const UpAxisEstimate& estimate, double max_spread,
                                           const std::vector<double>& pitches_deg) {
  std::vector<Eigen::Vector3d> axes;
  if (estimate.cameras == 0 || !(estimate.heading_spread < max_spread)) return axes;
  for (const double pitch : pitches_deg)
    axes.push_back((Eigen::AngleAxisd(pitch * M_PI / 180.0, estimate.rows.normalized()) * estimate.axis).normalized());
  return axes;
}

SharedUpAxes chooseUpAxes(const UpAxisEstimate& source_estimate, const UpAxisEstimate& target_estimate,
                          double z_tolerance_deg, double pitch_search_spread) {
  if (!(z_tolerance_deg >= 0.0 && z_tolerance_deg <= 90.0))
    throw std::invalid_argument("chooseUpAxes: z_tolerance_deg must be in [0, 90]");
  if (!(pitch_search_spread >= 0.0 && pitch_search_spread <= 0.5))
    throw std::invalid_argument("chooseUpAxes: pitch_search_spread must be in [0, 0.5]");
  const auto z_up = [&](const UpAxisEstimate& e) {
    return std::abs(e.axis.normalized().z()) >= std::cos(z_tolerance_deg * M_PI / 180.0);
  };
  SharedUpAxes axes;
  if (source_estimate.cameras == 0 || target_estimate.cameras == 0) return axes;
  if (z_up(source_estimate) && z_up(target_estimate)) {
    // Each map may be up to the tolerance off gravity, and a turn about gravity doubles a common tilt: searched
    // about z, the two can disagree by twice the tolerance (a map 6 deg off, turned 180 deg: 12 deg).
    axes.tilt_range_deg = std::min(2.0 * z_tolerance_deg, kMaxTiltRangeDeg);
    return axes;
  }
  axes.source = source_estimate.axis.normalized();
  axes.target = target_estimate.axis.normalized();
  axes.tilt_range_deg = 8.0;
  axes.also_try_z = true;
  // A map whose cameras face about one way fixes its up axis only to within a turn about their rows (their pitch,
  // or their roll over few headings: 22-37 deg off on mini-maps of fr3 and of the real map in its first camera's
  // frame); the search's tilts reach 8 deg, so the estimate is also searched turned about the rows.
  // When both maps' cameras face one way, both are turned by the same angle about their own rows: one camera's pitch
  // (the same robot, or the same hand-held habit) puts both estimates off alike.
  const std::vector<Eigen::Vector3d> source_pitched =
      pitchedUpAxes(source_estimate, pitch_search_spread, kPitchedLevellingsDeg);
  const std::vector<Eigen::Vector3d> target_pitched =
      pitchedUpAxes(target_estimate, pitch_search_spread, kPitchedLevellingsDeg);
  if (source_pitched.empty() && target_pitched.empty()) return axes;
  for (std::size_t k = 0; k < kPitchedLevellingsDeg.size(); ++k)
    axes.alternatives.emplace_back(source_pitched.empty() ? axes.source : source_pitched[k],
                                   target_pitched.empty() ? axes.target : target_pitched[k]);
  return axes;
}

}  // namespace weighted_icp
