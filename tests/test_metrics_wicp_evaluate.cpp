// Runs the built wicp_evaluate tool as a user would and checks its output
// and exit codes.

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <random>
#include <regex>
#include <sstream>
#include <string>

#include <sys/wait.h>

#include <gtest/gtest.h>

#include "test_support.h"
#include "tool_runner.h"
#include "weighted_icp/io/trajectory.h"

using namespace weighted_icp;
namespace fs = std::filesystem;

namespace {

using weighted_icp::testing::jsonNumber;
using weighted_icp::testing::lastLine;
using weighted_icp::testing::ToolRun;

ToolRun runEvaluate(const std::string& arguments, const fs::path& scratch) {
  return weighted_icp::testing::runBuiltTool("wicp_evaluate", arguments, scratch);
}

std::string quoted(const fs::path& path) { return "'" + path.string() + "'"; }

Eigen::Isometry3d knownMotion() {
  Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
  motion.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1.0, -2.0, 0.5).normalized()).toRotationMatrix();
  motion.translation() = Eigen::Vector3d(-1.5, 0.25, 2.0);
  return motion;
}

/// Every third pose of the ground truth (about the camera's rate), seen from
/// another world frame, with `noise` metres of Gaussian noise on each
/// coordinate; returns the RMS of the added position noise.
double writePerturbedCopy(const Trajectory& groundtruth, double noise, const fs::path& path) {
  std::mt19937 random(11);
  std::normal_distribution<double> gaussian(0.0, noise);
  Trajectory estimate;
  double sum_squares = 0.0;
  for (std::size_t k = 0; k < groundtruth.size(); k += 3) {
    StampedPose stamped = groundtruth[k];
    const Eigen::Vector3d offset(gaussian(random), gaussian(random), gaussian(random));
    stamped.pose.translation() += offset;
    stamped.pose = knownMotion() * stamped.pose;
    sum_squares += offset.squaredNorm();
    estimate.push_back(stamped);
  }
  io::writeTrajectory(estimate, path.string());
  return std::sqrt(sum_squares / static_cast<double>(estimate.size()));
}

const fs::path kGroundTruth = weighted_icp::testing::dataDir() / "tum_fr1_xyz_head" / "groundtruth.txt";

}  // namespace

TEST(WicpEvaluate, RigidlyMovedGroundTruthHasNoError) {
  WEIGHTED_ICP_REQUIRE_FILE(kGroundTruth);
  const fs::path dir = weighted_icp::testing::scratchDir("evaluate_exact");
  const Trajectory groundtruth = io::readTrajectory(kGroundTruth.string());
  writePerturbedCopy(groundtruth, 0.0, dir / "estimate.txt");
  const ToolRun run = runEvaluate(quoted(kGroundTruth) + " " + quoted(dir / "estimate.txt") + " --json", dir);
  ASSERT_EQ(run.status, 0) << run.err;
  const std::string json = lastLine(run.out);
  ASSERT_EQ(json.front(), '{') << run.out;
  ASSERT_EQ(json.back(), '}') << run.out;
  const std::size_t estimated_poses = (groundtruth.size() + 2) / 3;
  EXPECT_EQ(jsonNumber(json, "pairs"), static_cast<double>(estimated_poses));  // same timestamps: all pair
  EXPECT_EQ(jsonNumber(json, "estimate_poses"), static_cast<double>(estimated_poses));
  EXPECT_EQ(jsonNumber(json, "groundtruth_poses"), static_cast<double>(groundtruth.size()));
  EXPECT_LT(jsonNumber(json, "ate_rmse_m"), 1e-9);
  EXPECT_LT(jsonNumber(json, "ate_max_m"), 1e-9);
  EXPECT_GT(jsonNumber(json, "rpe_pairs"), 0.0);
  EXPECT_LT(jsonNumber(json, "rpe_translation_rmse_m"), 1e-9);
  EXPECT_LT(jsonNumber(json, "rpe_rotation_rmse_deg"), 1e-6);
  // The alignment undoes the known motion; its first row is in the JSON.
  const Eigen::Matrix4d expected = knownMotion().inverse().matrix();
  std::smatch row;
  ASSERT_TRUE(std::regex_search(json, row, std::regex("\"alignment\":\\[\\[([^\\]]*)\\]")));
  std::istringstream values(std::regex_replace(row[1].str(), std::regex(","), " "));
  for (int c = 0; c < 4; ++c) {
    double value;
    values >> value;
    EXPECT_NEAR(value, expected(0, c), 1e-9) << "column " << c;
  }
}

TEST(WicpEvaluate, NoisyCopyHasTheNoiseAsError) {
  WEIGHTED_ICP_REQUIRE_FILE(kGroundTruth);
  const fs::path dir = weighted_icp::testing::scratchDir("evaluate_noisy");
  const Trajectory groundtruth = io::readTrajectory(kGroundTruth.string());
  const double noise_rms = writePerturbedCopy(groundtruth, 0.01, dir / "estimate.txt");
  const ToolRun run = runEvaluate(quoted(kGroundTruth) + " " + quoted(dir / "estimate.txt") + " --json", dir);
  ASSERT_EQ(run.status, 0) << run.err;
  const std::string json = lastLine(run.out);
  // The identity alignment would leave exactly the noise; the best one no more.
  const double rmse = jsonNumber(json, "ate_rmse_m");
  EXPECT_LE(rmse, noise_rms * (1.0 + 1e-9));
  EXPECT_GT(rmse, 0.8 * noise_rms);
  EXPECT_LE(jsonNumber(json, "ate_median_m"), jsonNumber(json, "ate_max_m"));
  EXPECT_GT(jsonNumber(json, "rpe_translation_rmse_m"), 0.0);
  // The human-readable part states the same RMSE in centimetres.
  std::ostringstream centimetres;
  centimetres << std::fixed << std::setprecision(2) << 100.0 * rmse << " cm";
  EXPECT_NE(run.out.find(centimetres.str()), std::string::npos) << run.out;
}

TEST(WicpEvaluate, VersusAnotherEstimateSaysWhetherTheDifferenceIsBeyondTheScatter) {
  WEIGHTED_ICP_REQUIRE_FILE(kGroundTruth);
  const fs::path dir = weighted_icp::testing::scratchDir("evaluate_versus");
  const Trajectory groundtruth = io::readTrajectory(kGroundTruth.string());
  writePerturbedCopy(groundtruth, 0.001, dir / "precise.txt");
  writePerturbedCopy(groundtruth, 0.01, dir / "coarse.txt");
  const ToolRun run = runEvaluate(
      quoted(kGroundTruth) + " " + quoted(dir / "precise.txt") + " --versus " + quoted(dir / "coarse.txt") + " --json",
      dir);
  ASSERT_EQ(run.status, 0) << run.err;
  const std::string json = lastLine(run.out);
  EXPECT_EQ(jsonNumber(json, "common_poses"), jsonNumber(json, "pairs"));
  EXPECT_GT(jsonNumber(json, "versus_ate_rmse_m"), 5.0 * jsonNumber(json, "ate_rmse_m"));
  EXPECT_GT(jsonNumber(json, "estimate_lower_fraction"), 0.95);
  EXPECT_NE(run.out.find("lower beyond the scatter"), std::string::npos) << run.out;
  const ToolRun missing = runEvaluate(
      quoted(kGroundTruth) + " " + quoted(dir / "precise.txt") + " --versus " + quoted(dir / "none.txt"), dir);
  EXPECT_NE(missing.status, 0);
  EXPECT_NE(missing.err.find("none.txt"), std::string::npos) << missing.err;
}

TEST(WicpEvaluate, RpeDeltaInFramesIsAccepted) {
  WEIGHTED_ICP_REQUIRE_FILE(kGroundTruth);
  const fs::path dir = weighted_icp::testing::scratchDir("evaluate_frames");
  const Trajectory groundtruth = io::readTrajectory(kGroundTruth.string());
  writePerturbedCopy(groundtruth, 0.0, dir / "estimate.txt");
  const ToolRun run = runEvaluate(
      quoted(kGroundTruth) + " " + quoted(dir / "estimate.txt") + " --rpe-delta 5 --rpe-unit f --json", dir);
  ASSERT_EQ(run.status, 0) << run.err;
  // Pairs (i, i + 5) whose partner is not the last pose.
  EXPECT_EQ(jsonNumber(lastLine(run.out), "rpe_pairs"), static_cast<double>((groundtruth.size() + 2) / 3 - 6));
}

TEST(WicpEvaluate, BadInputGivesNonZeroExitAndNamesTheProblem) {
  WEIGHTED_ICP_REQUIRE_FILE(kGroundTruth);
  const fs::path dir = weighted_icp::testing::scratchDir("evaluate_bad_input");

  const fs::path missing = dir / "absent.txt";
  ToolRun run = runEvaluate(quoted(kGroundTruth) + " " + quoted(missing), dir);
  EXPECT_EQ(run.status, 1);
  EXPECT_NE(run.err.find(missing.string()), std::string::npos) << run.err;

  const fs::path malformed = dir / "malformed.txt";
  std::ofstream(malformed) << "# estimate\n1305031102.1759 1 2 3 0 0 0 1\n1305031102.2 1 2 x 0 0 0 1\n";
  run = runEvaluate(quoted(kGroundTruth) + " " + quoted(malformed), dir);
  EXPECT_EQ(run.status, 1);
  EXPECT_NE(run.err.find(malformed.string() + ":3:"), std::string::npos) << run.err;

  const fs::path elsewhere = dir / "elsewhere.txt";  // no timestamp near the ground truth
  std::ofstream(elsewhere) << "1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 0 1\n3.0 0 0 0 0 0 0 1\n4.0 0 0 0 0 0 0 1\n";
  run = runEvaluate(quoted(kGroundTruth) + " " + quoted(elsewhere), dir);
  EXPECT_EQ(run.status, 1);
  EXPECT_NE(run.err.find("at least 3"), std::string::npos) << run.err;

  // Command-line errors: exit code 2.
  EXPECT_EQ(runEvaluate(quoted(kGroundTruth), dir).status, 2);
  EXPECT_EQ(runEvaluate(quoted(kGroundTruth) + " " + quoted(kGroundTruth) + " --rpe-unit m", dir).status, 2);
  EXPECT_EQ(runEvaluate(quoted(kGroundTruth) + " " + quoted(kGroundTruth) + " --max-difference abc", dir).status, 2);
}
