#pragma once
// Trajectories in the TUM RGB-D benchmark's text format and their evaluation
// as the benchmark's tools do it (associate.py, evaluate_ate.py,
// evaluate_rpe.py with --fixed_delta).
//
//   timestamp tx ty tz qx qy qz qw
//     camera-to-world pose; the quaternion is scalar LAST (unlike the map
//     format). Blank lines and lines starting with '#' are skipped.

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

namespace weighted_icp::io {

struct StampedPose {
  double timestamp = 0.0;  // seconds
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  // camera to world
};
using Trajectory = std::vector<StampedPose>;

/// One data line of a TUM text file (rgb.txt, depth.txt, groundtruth.txt):
/// its timestamp, the fields after it, and its line number for errors.
struct TimestampedLine {
  double timestamp = 0.0;
  std::vector<std::string> fields;
  std::size_t line = 0;
};

/// Reads the data lines of a TUM text file, each a finite timestamp followed
/// by exactly `fields_after_timestamp` fields; timestamps must be unique.
/// Throws std::runtime_error "path:line: what is wrong" (or "path: cannot
/// open the file").
std::vector<TimestampedLine> readTimestampedLines(const std::string& path, std::size_t fields_after_timestamp);

/// Reads a trajectory in file order. Refuses (path:line) non-numbers,
/// non-finite values, quaternions far from unit norm and repeated timestamps.
Trajectory readTrajectory(const std::string& path);
/// Writes with round-trip precision, atomically; throws std::runtime_error
/// naming the path, also for a pose that is not a finite rigid motion.
void writeTrajectory(const Trajectory& trajectory, const std::string& path);

/// Index pairs (into `first`, into `second`) of timestamps that differ by
/// less than `max_difference`, as associate.py (offset 0): candidate pairs
/// taken greedily by increasing difference, each timestamp used at most once;
/// the result is sorted by the first timestamp. Throws std::invalid_argument
/// for a non-finite timestamp or a max_difference that is not > 0.
std::vector<std::pair<std::size_t, std::size_t>> associate(const std::vector<double>& first,
                                                           const std::vector<double>& second, double max_difference);
/// The same on the trajectories' timestamps.
std::vector<std::pair<std::size_t, std::size_t>> associate(const Trajectory& first, const Trajectory& second,
                                                           double max_difference);

/// Index of the pose of `sorted_trajectory` (sorted by time, not empty)
/// nearest in time to `timestamp`; the earlier one on a tie.
std::size_t nearestInTime(const Trajectory& sorted_trajectory, double timestamp);

/// Statistics of a set of non-negative errors.
struct ErrorStatistics {
  double rmse = 0.0, mean = 0.0, median = 0.0, max = 0.0;
};

struct AbsoluteTrajectoryError {
  std::size_t pairs = 0;  // associated (ground truth, estimate) poses
  ErrorStatistics translation;  // metres, after alignment
  /// The rigid motion (no scale) that best maps the estimated positions onto
  /// the ground-truth ones: ground truth ≈ alignment * estimate.
  Eigen::Isometry3d alignment = Eigen::Isometry3d::Identity();
};

/// evaluate_ate.py: associates by timestamp (as associate()), aligns the
/// estimated positions onto ground truth (Horn/Umeyama, no scale) and
/// measures the remaining position errors. Throws std::runtime_error when
/// fewer than 3 pairs associate, std::invalid_argument for non-finite poses.
AbsoluteTrajectoryError computeAte(const Trajectory& groundtruth, const Trajectory& estimate,
                                   double max_difference = 0.02);

enum class DeltaUnit { Seconds, Frames };

struct RelativePoseError {
  std::size_t pairs = 0;  // compared pose pairs (i, j)
  ErrorStatistics translation;  // metres
  ErrorStatistics rotation_deg;  // degrees
};

/// evaluate_rpe.py --fixed_delta: for each estimated pose i (by time), j is
/// the pose nearest to i + delta (seconds, or frames); as that script, pairs
/// whose j is the last pose are skipped (it cannot tell "last" from "past
/// the end"). Each estimated pose is compared with the ground-truth pose
/// nearest in time, if within twice the median ground-truth interval. The
/// error of a pair is (E_j^-1 E_i)^-1 (G_j^-1 G_i). Throws std::runtime_error
/// when fewer than 2 pairs remain, std::invalid_argument for a delta that is
/// not > 0 (or not a whole number of frames) and for non-finite poses.
RelativePoseError computeRpe(const Trajectory& groundtruth, const Trajectory& estimate, double delta = 1.0,
                             DeltaUnit unit = DeltaUnit::Seconds);

}  // namespace weighted_icp::io
