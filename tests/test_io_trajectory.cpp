#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <tuple>

#include <gtest/gtest.h>

#include "test_support.h"
#include "trajectory_fixtures.h"
#include "weighted_icp/io/trajectory.h"

using namespace weighted_icp;
using namespace weighted_icp::testing;
namespace fs = std::filesystem;
using Pairs = std::vector<std::pair<std::size_t, std::size_t>>;

namespace {

std::string writeText(const fs::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  return path.string();
}

std::string readError(const std::string& path) {
  try {
    io::readTrajectory(path);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return {};
}

/// associate.py transcribed literally: every pair compared, tuples sorted.
Pairs bruteForceAssociate(const std::vector<double>& first, const std::vector<double>& second, double max_difference) {
  std::vector<std::tuple<double, double, double, std::size_t, std::size_t>> candidates;
  for (std::size_t i = 0; i < first.size(); ++i)
    for (std::size_t j = 0; j < second.size(); ++j)
      if (std::abs(first[i] - second[j]) < max_difference)
        candidates.emplace_back(std::abs(first[i] - second[j]), first[i], second[j], i, j);
  std::sort(candidates.begin(), candidates.end());
  std::vector<bool> first_used(first.size()), second_used(second.size());
  std::vector<std::tuple<double, double, std::size_t, std::size_t>> matches;
  for (const auto& [difference, a, b, i, j] : candidates) {
    if (first_used[i] || second_used[j]) continue;
    first_used[i] = second_used[j] = true;
    matches.emplace_back(a, b, i, j);
  }
  std::sort(matches.begin(), matches.end());
  Pairs result;
  for (const auto& [a, b, i, j] : matches) result.emplace_back(i, j);
  return result;
}

}  // namespace

TEST(Trajectory, RoundTripKeepsTimestampsAndPoses) {
  const auto dir = weighted_icp::testing::scratchDir("trajectory_round_trip");
  const Trajectory trajectory = curvedTrajectory(50);
  const std::string path = (dir / "trajectory.txt").string();
  io::writeTrajectory(trajectory, path);
  const Trajectory read = io::readTrajectory(path);
  ASSERT_EQ(read.size(), trajectory.size());
  for (std::size_t k = 0; k < read.size(); ++k) {
    EXPECT_EQ(read[k].timestamp, trajectory[k].timestamp);
    EXPECT_EQ(read[k].pose.translation(), trajectory[k].pose.translation());
    EXPECT_TRUE(read[k].pose.linear().isApprox(trajectory[k].pose.linear(), 1e-14));
  }
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);  // no temporary left
}

TEST(Trajectory, ReadsQuaternionsScalarLast) {
  const auto dir = weighted_icp::testing::scratchDir("trajectory_scalar_last");
  // 90 degrees about z: qz = qw = sqrt(1/2).
  const std::string path = writeText(dir / "t.txt",
                                     "# timestamp tx ty tz qx qy qz qw\n\n"
                                     "10.5 1 2 3 0 0 0.70710678 0.70710678\n");
  const Trajectory trajectory = io::readTrajectory(path);
  ASSERT_EQ(trajectory.size(), 1u);
  EXPECT_EQ(trajectory[0].timestamp, 10.5);
  EXPECT_TRUE(trajectory[0].pose.translation().isApprox(Eigen::Vector3d(1, 2, 3)));
  EXPECT_TRUE((trajectory[0].pose.linear() * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY(), 1e-7));
}

TEST(Trajectory, ReadsTheRealGroundTruth) {
  const fs::path path = weighted_icp::testing::dataDir() / "tum_fr1_xyz_head" / "groundtruth.txt";
  WEIGHTED_ICP_REQUIRE_FILE(path);
  std::ifstream in(path);
  std::size_t data_lines = 0;
  std::string line, first_data_line;
  while (std::getline(in, line))
    if (!line.empty() && line[0] != '#' && data_lines++ == 0) first_data_line = line;
  const Trajectory trajectory = io::readTrajectory(path.string());
  ASSERT_EQ(trajectory.size(), data_lines);
  std::istringstream fields(first_data_line);
  double timestamp, tx, ty, tz;
  fields >> timestamp >> tx >> ty >> tz;
  EXPECT_EQ(trajectory[0].timestamp, timestamp);
  EXPECT_TRUE(trajectory[0].pose.translation().isApprox(Eigen::Vector3d(tx, ty, tz)));
}

TEST(Trajectory, MalformedLinesNameFileAndLine) {
  const auto dir = weighted_icp::testing::scratchDir("trajectory_malformed");
  const std::string good = "# header\n1.0 0 0 0 0 0 0 1\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"1.1 0 0 0 0 0 1\n", "field"},                        // qw missing
      {"1.1 0 0 zero 0 0 0 1\n", "tz 'zero'"},               // not a number
      {"1.1 0 nan 0 0 0 0 1\n", "ty"},                       // not finite
      {"1.1 0 0 0 0 0 0 0\n", "quaternion"},                 // no rotation
      {"1.0 0 0 0 0 0 0 1\n", "already appears on line 2"},  // repeated timestamp
      {"1.1 0 0 0 0 0 0 1 7\n", "field"},                    // one field too many
  };
  for (std::size_t c = 0; c < cases.size(); ++c) {
    const std::string path = writeText(dir / ("case" + std::to_string(c) + ".txt"), good + cases[c].first);
    const std::string error = readError(path);
    EXPECT_NE(error.find(path + ":3:"), std::string::npos) << error;
    EXPECT_NE(error.find(cases[c].second), std::string::npos) << error;
  }
  const std::string missing = (dir / "absent.txt").string();
  EXPECT_NE(readError(missing).find(missing), std::string::npos);
}

// Issue #10: a token is echoed clipped to a few bytes and with \xNN for bytes
// that are not printable, so a NUL does not cut the message short.
TEST(Trajectory, BadTokensAreClippedAndEscaped) {
  const auto dir = weighted_icp::testing::scratchDir("trajectory_bad_tokens");
  const std::string huge =
      readError(writeText(dir / "huge.txt", "1.0 0 0 " + std::string(1 << 20, 'z') + " 0 0 0 1\n"));
  EXPECT_LT(huge.size(), 200u + dir.string().size()) << huge;
  EXPECT_NE(huge.find("tz 'zzzz"), std::string::npos) << huge;
  EXPECT_NE(huge.find("(1048576 bytes) is not a number"), std::string::npos) << huge;
  const std::string nul =
      readError(writeText(dir / "nul.txt", "1.0 0 0 " + std::string("4\0\x7f\x80", 4) + " 0 0 0 1\n"));
  EXPECT_NE(nul.find("tz '4\\x00\\x7f\\x80' is not a number"), std::string::npos) << nul;
}

TEST(Trajectory, NonRigidPosesAreNotWritten) {
  const auto dir = weighted_icp::testing::scratchDir("trajectory_write_invalid");
  Trajectory trajectory = curvedTrajectory(3);
  trajectory[1].pose.translation().x() = std::numeric_limits<double>::quiet_NaN();
  const std::string path = (dir / "t.txt").string();
  EXPECT_THROW(io::writeTrajectory(trajectory, path), std::runtime_error);
  trajectory = curvedTrajectory(3);
  trajectory[2].pose.linear() *= 2.0;
  EXPECT_THROW(io::writeTrajectory(trajectory, path), std::runtime_error);
  EXPECT_FALSE(fs::exists(path));
}

TEST(TrajectoryAssociate, TakesPairsByIncreasingDifference) {
  // 1.010 and 1.008 differ least, so 1.000 is left without a partner even
  // though 1.008 is its nearest timestamp.
  EXPECT_EQ(io::associate(std::vector<double>{1.000, 1.010}, std::vector<double>{1.008}, 0.02), (Pairs{{1, 0}}));
  // Each timestamp at most once; unpaired ones are dropped.
  EXPECT_EQ(io::associate(std::vector<double>{1.0, 2.0, 3.0}, std::vector<double>{3.01, 1.005, 2.5}, 0.02),
            (Pairs{{0, 1}, {2, 0}}));
  // Sorted by the first list's timestamps, whatever the input order.
  EXPECT_EQ(io::associate(std::vector<double>{3.0, 1.0}, std::vector<double>{1.001, 3.001}, 0.02),
            (Pairs{{1, 0}, {0, 1}}));
  // The difference must be strictly below the limit (0.5 and 0.25 are exact in binary).
  EXPECT_TRUE(io::associate(std::vector<double>{1.0}, std::vector<double>{1.5}, 0.5).empty());
  EXPECT_EQ(io::associate(std::vector<double>{1.0}, std::vector<double>{1.25}, 0.5), (Pairs{{0, 0}}));
}

TEST(TrajectoryAssociate, MatchesALiteralTranscriptionOfAssociatePy) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> jitter(-0.02, 0.02);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<double> first, second;
    for (int k = 0; k < 200; ++k) {
      first.push_back(100.0 + 0.033 * k + jitter(random));
      if (k % 7 != 3) second.push_back(100.0 + 0.033 * k + jitter(random));
    }
    std::shuffle(second.begin(), second.end(), random);
    EXPECT_EQ(io::associate(first, second, 0.02), bruteForceAssociate(first, second, 0.02));
  }
}

// Found by fuzz/fuzz_trajectory: with a limit below the spacing of doubles
// at the timestamps (1e-9 s at 1.3e9 s), equal timestamps were not paired.
TEST(TrajectoryAssociate, PairsEqualTimestampsWhateverTheLimit) {
  const std::vector<double> stamps{1305031101.1759, 1305031101.1858, 0.5, 1e300};
  for (const double limit : {1e-9, 1e-300, 0.02})
    EXPECT_EQ(io::associate(stamps, stamps, limit), bruteForceAssociate(stamps, stamps, limit)) << limit;
  EXPECT_EQ(io::associate(stamps, stamps, 1e-9).size(), stamps.size());
}

TEST(TrajectoryAssociate, RefusesBadInput) {
  const std::vector<double> stamps{1.0, 2.0};
  EXPECT_THROW(io::associate(stamps, stamps, 0.0), std::invalid_argument);
  EXPECT_THROW(io::associate(stamps, stamps, -1.0), std::invalid_argument);
  EXPECT_THROW(io::associate(stamps, stamps, std::numeric_limits<double>::infinity()), std::invalid_argument);
  EXPECT_THROW(io::associate(stamps, std::vector<double>{std::nan("")}, 0.02), std::invalid_argument);
}

TEST(TrajectoryNearestInTime, FindsTheClosestPose) {
  Trajectory trajectory;
  for (int i = 0; i < 5; ++i) trajectory.push_back({50.0 + 0.1 * i, Eigen::Isometry3d::Identity()});
  EXPECT_EQ(io::nearestInTime(trajectory, 0.0), 0u);
  EXPECT_EQ(io::nearestInTime(trajectory, 50.13), 1u);
  EXPECT_EQ(io::nearestInTime(trajectory, 50.17), 2u);
  EXPECT_EQ(io::nearestInTime(trajectory, 99.0), 4u);
  EXPECT_THROW(io::nearestInTime(Trajectory{}, 1.0), std::invalid_argument);
}
