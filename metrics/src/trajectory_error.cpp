// The TUM benchmark's trajectory errors: ATE after rigid alignment, RPE over a fixed delta.
#include "weighted_icp/metrics/trajectory_error.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

namespace weighted_icp::metrics {

using io::StampedPose;
using io::Trajectory;

namespace {

/// Shortest text that reads back to the same double, for the messages.
std::string exact(double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, result.ptr);
}

/// `trajectory` ordered by time.
Trajectory sortedByTime(Trajectory trajectory) {
  std::stable_sort(trajectory.begin(), trajectory.end(),
                   [](const StampedPose& a, const StampedPose& b) { return a.timestamp < b.timestamp; });
  return trajectory;
}

}  // namespace

AbsoluteTrajectoryError computeAte(const Trajectory& groundtruth, const Trajectory& estimate, double max_difference) {
  io::requireFiniteTrajectory(groundtruth, "ground-truth");
  io::requireFiniteTrajectory(estimate, "estimated");
  const auto matches = io::associate(groundtruth, estimate, max_difference);
  if (matches.size() < 3)
    throw std::runtime_error("only " + std::to_string(matches.size()) + " of " + std::to_string(estimate.size()) +
                             " estimated poses have a ground-truth pose within " + exact(max_difference) +
                             " s; the absolute trajectory error needs at least 3");
  const auto n = static_cast<Eigen::Index>(matches.size());
  Eigen::Matrix3Xd estimated_positions(3, n), true_positions(3, n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const auto [g, e] = matches[static_cast<std::size_t>(k)];
    true_positions.col(k) = groundtruth[g].pose.translation();
    estimated_positions.col(k) = estimate[e].pose.translation();
  }
  AbsoluteTrajectoryError result;
  result.pairs = matches.size();
  result.alignment.matrix() = Eigen::umeyama(estimated_positions, true_positions, false);
  std::vector<double> errors(matches.size());
  for (Eigen::Index k = 0; k < n; ++k)
    errors[static_cast<std::size_t>(k)] =
        (result.alignment * estimated_positions.col(k) - true_positions.col(k)).norm();
  result.translation = summarizeErrors(std::move(errors));
  return result;
}

RelativePoseError computeRpe(const Trajectory& groundtruth, const Trajectory& estimate, double delta, DeltaUnit unit) {
  io::requireFiniteTrajectory(groundtruth, "ground-truth");
  io::requireFiniteTrajectory(estimate, "estimated");
  if (!(std::isfinite(delta) && delta > 0.0) || (unit == DeltaUnit::Frames && delta != std::floor(delta)))
    throw std::invalid_argument("the RPE delta must be > 0" +
                                std::string(unit == DeltaUnit::Frames ? " and a whole number of frames" : " seconds") +
                                ", not " + exact(delta));
  if (groundtruth.size() < 2) throw std::runtime_error("the relative pose error needs at least 2 ground-truth poses");
  if (estimate.empty()) throw std::runtime_error("the estimated trajectory is empty");

  const Trajectory truth = sortedByTime(groundtruth);
  const Trajectory estimated = sortedByTime(estimate);
  std::vector<double> intervals(truth.size() - 1);
  for (std::size_t k = 0; k + 1 < truth.size(); ++k) intervals[k] = truth[k + 1].timestamp - truth[k].timestamp;
  const double max_time_difference = 2.0 * median(intervals);

  std::vector<double> translation_errors, rotation_errors_deg;
  for (std::size_t i = 0; i < estimated.size(); ++i) {
    // As evaluate_rpe.py: j is the pose nearest to i + delta, clamped to the last.
    const double last = static_cast<double>(estimated.size() - 1);
    const std::size_t j = unit == DeltaUnit::Frames
                              ? static_cast<std::size_t>(std::min(static_cast<double>(i) + delta, last))
                              : io::nearestInTime(estimated, estimated[i].timestamp + delta);
    if (j == estimated.size() - 1) continue;
    const std::size_t gi = io::nearestInTime(truth, estimated[i].timestamp);
    const std::size_t gj = io::nearestInTime(truth, estimated[j].timestamp);
    if (std::abs(truth[gi].timestamp - estimated[i].timestamp) > max_time_difference ||
        std::abs(truth[gj].timestamp - estimated[j].timestamp) > max_time_difference)
      continue;
    const Eigen::Isometry3d estimated_motion = estimated[j].pose.inverse() * estimated[i].pose;
    const Eigen::Isometry3d true_motion = truth[gj].pose.inverse() * truth[gi].pose;
    const Eigen::Isometry3d error = estimated_motion.inverse() * true_motion;
    translation_errors.push_back(error.translation().norm());
    // The angle via AngleAxis rather than acos((trace - 1) / 2): the same
    // quantity, without acos's loss of precision near zero.
    rotation_errors_deg.push_back(Eigen::AngleAxisd(error.linear()).angle() * 180.0 / EIGEN_PI);
  }
  if (translation_errors.size() < 2)
    throw std::runtime_error("only " + std::to_string(translation_errors.size()) + " pose pair(s) " + exact(delta) +
                             (unit == DeltaUnit::Seconds ? " s" : " frame(s)") +
                             " apart have ground truth; the relative pose error needs at least 2");
  RelativePoseError result;
  result.pairs = translation_errors.size();
  result.translation = summarizeErrors(std::move(translation_errors));
  result.rotation_deg = summarizeErrors(std::move(rotation_errors_deg));
  return result;
}

}  // namespace weighted_icp::metrics
