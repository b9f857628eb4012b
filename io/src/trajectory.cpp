#include "weighted_icp/io/trajectory.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <numeric>
#include <stdexcept>
#include <string_view>
#include <unordered_map>

#include "text_fields.h"
#include "weighted_icp/io/atomic_file.h"

namespace weighted_icp::io {

namespace {

[[noreturn]] void failAt(const std::string& path, std::size_t line, const std::string& what) {
  throw std::runtime_error(path + ":" + std::to_string(line) + ": " + what);
}

double finiteNumber(const std::string& text, const char* name, const std::string& path, std::size_t line) {
  double value = 0.0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size())
    failAt(path, line, std::string(name) + " " + detail::quoteToken(text) + " is not a number");
  if (!std::isfinite(value))
    failAt(path, line, std::string(name) + " is " + detail::clipToken(text) + "; it must be finite");
  return value;
}

using detail::exact;

bool isFiniteRigidMotion(const Eigen::Isometry3d& pose) {
  const Eigen::Matrix3d rotation = pose.linear();
  // Poses chained over a long run drift from orthonormal by far less than this.
  return pose.matrix().allFinite() && rotation.isUnitary(1e-6) && rotation.determinant() > 0.0;
}

std::vector<double> timestamps(const Trajectory& trajectory) {
  std::vector<double> stamps;
  stamps.reserve(trajectory.size());
  for (const auto& stamped : trajectory) stamps.push_back(stamped.timestamp);
  return stamps;
}

}  // namespace

std::vector<TimestampedLine> readTimestampedLines(const std::string& path, std::size_t fields_after_timestamp) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open the file");
  std::vector<TimestampedLine> lines;
  std::unordered_map<double, std::size_t> line_of_timestamp;
  std::string text;
  std::size_t line_number = 0;
  while (std::getline(in, text)) {
    ++line_number;
    std::vector<std::string> fields;
    for (const std::string_view field : detail::splitFields(text)) fields.emplace_back(field);
    if (fields.empty() || fields[0].front() == '#') continue;
    if (fields.size() != fields_after_timestamp + 1)
      failAt(path, line_number,
             "expected a timestamp and " + std::to_string(fields_after_timestamp) + " field(s), found " +
                 std::to_string(fields.size()) + " field(s) in all");
    TimestampedLine line;
    line.timestamp = finiteNumber(fields[0], "timestamp", path, line_number);
    line.line = line_number;
    const auto [previous, inserted] = line_of_timestamp.emplace(line.timestamp, line_number);
    if (!inserted)
      failAt(
          path, line_number,
          "timestamp " + detail::clipToken(fields[0]) + " already appears on line " + std::to_string(previous->second));
    line.fields.assign(std::make_move_iterator(fields.begin() + 1), std::make_move_iterator(fields.end()));
    lines.push_back(std::move(line));
  }
  if (in.bad()) throw std::runtime_error(path + ": read error");
  return lines;
}

Trajectory readTrajectory(const std::string& path) {
  static const char* const names[7] = {"tx", "ty", "tz", "qx", "qy", "qz", "qw"};
  Trajectory trajectory;
  for (const auto& line : readTimestampedLines(path, 7)) {
    double values[7];
    for (int i = 0; i < 7; ++i)
      values[i] = finiteNumber(line.fields[static_cast<std::size_t>(i)], names[i], path, line.line);
    const Eigen::Quaterniond q(values[6], values[3], values[4], values[5]);
    // Ground truth is written with 4 decimals, so unit to ~1e-4; far from unit
    // means a wrong line, not rounding.
    if (std::abs(q.norm() - 1.0) > 1e-2)
      failAt(path, line.line, "quaternion (qx qy qz qw) has norm " + std::to_string(q.norm()) + "; expected 1");
    StampedPose stamped;
    stamped.timestamp = line.timestamp;
    stamped.pose.linear() = q.normalized().toRotationMatrix();
    stamped.pose.translation() = Eigen::Vector3d(values[0], values[1], values[2]);
    trajectory.push_back(stamped);
  }
  return trajectory;
}

void writeTrajectory(const Trajectory& trajectory, const std::string& path) {
  try {
    requireFiniteTrajectory(trajectory, "trajectory");
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error("cannot write " + path + ": " + e.what());
  }
  writeAtomically(path, [&](const std::string& temporary) {
    std::ofstream out(temporary);
    if (!out) throw std::runtime_error("cannot create " + temporary);
    out << "# timestamp tx ty tz qx qy qz qw\n";
    for (const auto& [timestamp, pose] : trajectory) {
      const Eigen::Quaterniond q = Eigen::Quaterniond(Eigen::Matrix3d(pose.linear())).normalized();
      const Eigen::Vector3d& t = pose.translation();
      out << exact(timestamp) << ' ' << exact(t.x()) << ' ' << exact(t.y()) << ' ' << exact(t.z()) << ' '
          << exact(q.x()) << ' ' << exact(q.y()) << ' ' << exact(q.z()) << ' ' << exact(q.w()) << '\n';
    }
    out.close();
    if (!out) throw std::runtime_error("cannot write " + path);
  });
}

void requireFiniteTrajectory(const Trajectory& trajectory, const std::string& name) {
  for (const auto& stamped : trajectory)
    if (!std::isfinite(stamped.timestamp) || !isFiniteRigidMotion(stamped.pose))
      throw std::invalid_argument(name + " pose at timestamp " + exact(stamped.timestamp) +
                                  " is not a finite rigid motion");
}

std::size_t nearestInTime(const Trajectory& sorted_trajectory, double timestamp) {
  if (sorted_trajectory.empty()) throw std::invalid_argument("no nearest pose in an empty trajectory");
  const auto after = std::lower_bound(sorted_trajectory.begin(), sorted_trajectory.end(), timestamp,
                                      [](const StampedPose& pose, double t) { return pose.timestamp < t; });
  if (after == sorted_trajectory.begin()) return 0;
  if (after == sorted_trajectory.end()) return sorted_trajectory.size() - 1;
  const auto before = after - 1;
  const auto nearest = timestamp - before->timestamp <= after->timestamp - timestamp ? before : after;
  return static_cast<std::size_t>(nearest - sorted_trajectory.begin());
}

std::vector<std::pair<std::size_t, std::size_t>> associate(const std::vector<double>& first,
                                                           const std::vector<double>& second, double max_difference) {
  if (!(std::isfinite(max_difference) && max_difference > 0.0))
    throw std::invalid_argument("the maximum timestamp difference must be a finite number > 0, not " +
                                exact(max_difference));
  const auto all_finite = [](const std::vector<double>& values) {
    return std::all_of(values.begin(), values.end(), [](double v) { return std::isfinite(v); });
  };
  if (!all_finite(first) || !all_finite(second)) throw std::invalid_argument("cannot associate non-finite timestamps");

  std::vector<std::size_t> second_by_time(second.size());
  std::iota(second_by_time.begin(), second_by_time.end(), 0);
  std::sort(second_by_time.begin(), second_by_time.end(), [&](auto a, auto b) { return second[a] < second[b]; });

  // associate.py compares every pair; only the neighbours within the limit
  // can qualify, so scan a window (widened, so rounding cannot drop one; its
  // end is inclusive, since a limit below the timestamps' spacing of doubles
  // collapses it to the timestamp itself, which equal timestamps match).
  struct Candidate {
    double difference;
    std::size_t i, j;
  };
  std::vector<Candidate> candidates;
  for (std::size_t i = 0; i < first.size(); ++i) {
    auto k = std::lower_bound(second_by_time.begin(), second_by_time.end(), first[i] - 2.0 * max_difference,
                              [&](std::size_t j, double t) { return second[j] < t; });
    for (; k != second_by_time.end() && second[*k] <= first[i] + 2.0 * max_difference; ++k) {
      const double difference = std::abs(first[i] - second[*k]);
      if (difference < max_difference) candidates.push_back({difference, i, *k});
    }
  }
  // Python sorts the tuples (difference, a, b): ties go to the earlier timestamps.
  std::sort(candidates.begin(), candidates.end(), [&](const Candidate& a, const Candidate& b) {
    if (a.difference != b.difference) return a.difference < b.difference;
    if (first[a.i] != first[b.i]) return first[a.i] < first[b.i];
    if (second[a.j] != second[b.j]) return second[a.j] < second[b.j];
    return std::make_pair(a.i, a.j) < std::make_pair(b.i, b.j);
  });
  std::vector<bool> first_used(first.size()), second_used(second.size());
  std::vector<std::pair<std::size_t, std::size_t>> matches;
  for (const auto& c : candidates) {
    if (first_used[c.i] || second_used[c.j]) continue;
    first_used[c.i] = second_used[c.j] = true;
    matches.emplace_back(c.i, c.j);
  }
  std::sort(matches.begin(), matches.end(), [&](const auto& a, const auto& b) {
    return std::make_pair(first[a.first], second[a.second]) < std::make_pair(first[b.first], second[b.second]);
  });
  return matches;
}

std::vector<std::pair<std::size_t, std::size_t>> associate(const Trajectory& first, const Trajectory& second,
                                                           double max_difference) {
  return associate(timestamps(first), timestamps(second), max_difference);
}

}  // namespace weighted_icp::io
