#pragma once
// Trajectories in the TUM RGB-D benchmark's text format, and timestamp
// association as its associate.py does it. Their evaluation (ATE, RPE) is in
// weighted_icp::metrics (weighted_icp/metrics/trajectory_error.h).
//
//   timestamp tx ty tz qx qy qz qw
//     camera-to-world pose; the quaternion is scalar LAST (unlike the map
//     format). Blank lines and lines starting with '#' are skipped.

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "weighted_icp/core/trajectory.h"

namespace weighted_icp::io {

// The types moved to core; these names keep io::StampedPose and
// io::Trajectory working for one release.
using weighted_icp::StampedPose;
using weighted_icp::Trajectory;

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

/// Throws std::invalid_argument "<name> pose at timestamp T is not a finite
/// rigid motion" for the first pose with a non-finite timestamp or a matrix
/// that is not a finite rotation and translation.
void requireFiniteTrajectory(const Trajectory& trajectory, const std::string& name);

}  // namespace weighted_icp::io
