// The TUM benchmark's trajectory errors: ATE after rigid alignment, RPE over a fixed delta.
#include "weighted_icp/metrics/trajectory_error.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <map>
#include <random>
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

namespace {

/// The ATE's pose errors, each with the ground-truth pose it was paired with.
struct AlignedErrors {
  AbsoluteTrajectoryError ate;
  std::vector<std::size_t> truth_index;  // per error
  std::vector<double> errors;            // metres, after alignment
};

AlignedErrors alignedErrors(const Trajectory& groundtruth, const Trajectory& estimate, double max_difference) {
  io::requireFiniteTrajectory(groundtruth, "ground-truth");
  io::requireFiniteTrajectory(estimate, "estimated");
  const auto matches = io::associate(groundtruth, estimate, max_difference);
  if (matches.size() < 3)
    throw std::runtime_error("only " + std::to_string(matches.size()) + " of " + std::to_string(estimate.size()) +
                             " estimated poses have a ground-truth pose within " + exact(max_difference) +
                             " s; the absolute trajectory error needs at least 3");
  const auto n = static_cast<Eigen::Index>(matches.size());
  Eigen::Matrix3Xd estimated_positions(3, n), true_positions(3, n);
  AlignedErrors result;
  for (Eigen::Index k = 0; k < n; ++k) {
    const auto [g, e] = matches[static_cast<std::size_t>(k)];
    true_positions.col(k) = groundtruth[g].pose.translation();
    estimated_positions.col(k) = estimate[e].pose.translation();
    result.truth_index.push_back(g);
  }
  result.ate.pairs = matches.size();
  result.ate.alignment.matrix() = Eigen::umeyama(estimated_positions, true_positions, false);
  result.errors.resize(matches.size());
  for (Eigen::Index k = 0; k < n; ++k)
    result.errors[static_cast<std::size_t>(k)] =
        (result.ate.alignment * estimated_positions.col(k) - true_positions.col(k)).norm();
  result.ate.translation = summarizeErrors(result.errors);
  return result;
}

double rms(const std::vector<double>& values, const std::vector<std::size_t>& picks) {
  double sum = 0.0;
  for (const std::size_t k : picks) sum += values[k] * values[k];
  return std::sqrt(sum / static_cast<double>(picks.size()));
}

double correlation(const std::vector<double>& a, const std::vector<double>& b) {
  const double n = static_cast<double>(a.size());
  double mean_a = 0.0, mean_b = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    mean_a += a[k] / n;
    mean_b += b[k] / n;
  }
  double ab = 0.0, aa = 0.0, bb = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    ab += (a[k] - mean_a) * (b[k] - mean_b);
    aa += (a[k] - mean_a) * (a[k] - mean_a);
    bb += (b[k] - mean_b) * (b[k] - mean_b);
  }
  return aa > 0.0 && bb > 0.0 ? ab / std::sqrt(aa * bb) : std::numeric_limits<double>::quiet_NaN();
}

/// The fraction of resamples of the poses in which errors_a's RMSE is the lower (ties count half). Resampling whole
/// poses keeps what both share at a pose (the ground truth's own error, a frame hard for both) on both sides of each
/// comparison: only how the estimates differ decides. Trajectory errors drift slowly, so runs of consecutive poses
/// are drawn (a moving-block bootstrap, blocks of n^(1/3) poses): single poses drawn alone would take 32 correlated
/// poses for 32 independent ones and claim differences the sequence cannot show. Seeded: deterministic.
double firstLowerFraction(const std::vector<double>& errors_a, const std::vector<double>& errors_b,
                          std::size_t resamples) {
  const std::size_t n = errors_a.size();
  const auto block = static_cast<std::size_t>(std::ceil(std::cbrt(static_cast<double>(n))));
  std::mt19937 random(1);
  std::uniform_int_distribution<std::size_t> start(0, n - block);
  double first_lower = 0.0;
  std::vector<std::size_t> sample;
  sample.reserve(n + block);
  for (std::size_t r = 0; r < resamples; ++r) {
    sample.clear();
    while (sample.size() < n)
      for (std::size_t k = start(random), end = k + block; k < end; ++k) sample.push_back(k);
    sample.resize(n);
    const double rmse_a = rms(errors_a, sample), rmse_b = rms(errors_b, sample);
    first_lower += rmse_a < rmse_b ? 1.0 : rmse_a == rmse_b ? 0.5 : 0.0;
  }
  return first_lower / static_cast<double>(resamples);
}

}  // namespace

AbsoluteTrajectoryError computeAte(const Trajectory& groundtruth, const Trajectory& estimate, double max_difference) {
  return alignedErrors(groundtruth, estimate, max_difference).ate;
}

AteComparison compareAte(const Trajectory& groundtruth, const Trajectory& first, const Trajectory& second,
                         double max_difference, std::size_t resamples) {
  if (resamples == 0) throw std::invalid_argument("compareAte: resamples must be > 0");
  const AlignedErrors a = alignedErrors(groundtruth, first, max_difference);
  const AlignedErrors b = alignedErrors(groundtruth, second, max_difference);
  // The poses both were paired with, each estimate aligned on its own as the ATE is, in the time order of the
  // first's pairs (io::associate sorts them by the ground truth's timestamps).
  std::map<std::size_t, double> second_at;
  for (std::size_t j = 0; j < b.truth_index.size(); ++j) second_at.emplace(b.truth_index[j], b.errors[j]);
  std::vector<double> errors_a, errors_b;
  for (std::size_t i = 0; i < a.truth_index.size(); ++i)
    if (const auto found = second_at.find(a.truth_index[i]); found != second_at.end()) {
      errors_a.push_back(a.errors[i]);
      errors_b.push_back(found->second);
    }
  if (errors_a.size() < 3)
    throw std::runtime_error("only " + std::to_string(errors_a.size()) +
                             " ground-truth poses are paired with both estimates; a comparison needs at least 3");
  AteComparison result;
  result.first = a.ate;
  result.second = b.ate;
  result.common_poses = errors_a.size();
  std::vector<std::size_t> all(errors_a.size());
  for (std::size_t k = 0; k < all.size(); ++k) all[k] = k;
  result.first_rmse_m = rms(errors_a, all);
  result.second_rmse_m = rms(errors_b, all);
  result.error_correlation = correlation(errors_a, errors_b);
  result.first_lower_fraction = firstLowerFraction(errors_a, errors_b, resamples);
  result.resamples = resamples;
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
