// ATE and RPE against the TUM benchmark's definitions: rigid alignment,
// association by timestamp, fixed-delta pairs, and what is refused.
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "trajectory_fixtures.h"
#include "weighted_icp/io/trajectory.h"
#include "weighted_icp/metrics/trajectory_error.h"

using namespace weighted_icp;
using namespace weighted_icp::testing;

TEST(TrajectoryAte, RigidlyMovedTrajectoryHasNoErrorAndTheAlignmentUndoesTheMotion) {
  const Trajectory truth = curvedTrajectory(60);
  const Eigen::Isometry3d motion = rigidMotion(0.5, -2.0, 1.0, 0.3, -0.2, 1.1);
  const metrics::AbsoluteTrajectoryError ate = metrics::computeAte(truth, moved(truth, motion));
  EXPECT_EQ(ate.pairs, truth.size());
  EXPECT_LT(ate.translation.rmse, 1e-9);
  EXPECT_LT(ate.translation.max, 1e-9);
  EXPECT_TRUE(ate.alignment.isApprox(motion.inverse(), 1e-9)) << ate.alignment.matrix();
}

TEST(TrajectoryAte, ErrorOfAddedNoiseIsTheNoiseRms) {
  const Trajectory truth = curvedTrajectory(2000);
  Trajectory estimate = truth;
  std::mt19937 random(3);
  std::normal_distribution<double> noise(0.0, 0.01);
  double sum_squares = 0.0;
  for (auto& stamped : estimate) {
    const Eigen::Vector3d offset(noise(random), noise(random), noise(random));
    stamped.pose.translation() += offset;
    sum_squares += offset.squaredNorm();
  }
  const double noise_rms = std::sqrt(sum_squares / static_cast<double>(estimate.size()));
  const metrics::AbsoluteTrajectoryError ate =
      metrics::computeAte(truth, moved(estimate, rigidMotion(3.0, 1.0, -1.0, 0.0, 0.4, -0.7)));
  // The identity alignment leaves exactly the noise, and the best one cannot
  // do worse; six degrees of freedom over 2000 poses absorb little of it.
  EXPECT_LE(ate.translation.rmse, noise_rms * (1.0 + 1e-9));
  EXPECT_GT(ate.translation.rmse, 0.97 * noise_rms);
  EXPECT_LE(ate.translation.mean, ate.translation.rmse);
  EXPECT_LE(ate.translation.median, ate.translation.max);
  EXPECT_GT(ate.translation.max, ate.translation.rmse);
}

TEST(TrajectoryAte, AlignmentHasNoScale) {
  const Trajectory truth = curvedTrajectory(100);
  Trajectory estimate = truth;
  for (auto& stamped : estimate) stamped.pose.translation() *= 2.0;
  const metrics::AbsoluteTrajectoryError ate = metrics::computeAte(truth, estimate);
  const Eigen::Matrix3d rotation = ate.alignment.linear();
  EXPECT_TRUE((rotation.transpose() * rotation).isIdentity(1e-9));
  EXPECT_NEAR(rotation.determinant(), 1.0, 1e-9);
  EXPECT_GT(ate.translation.rmse, 0.1);  // a scaled copy cannot be matched without scale
}

TEST(TrajectoryAte, AssociatesByTimestamp) {
  const Trajectory truth = curvedTrajectory(40);
  Trajectory estimate = truth;
  for (auto& stamped : estimate) stamped.timestamp += 0.005;
  EXPECT_EQ(metrics::computeAte(truth, estimate).pairs, truth.size());
  EXPECT_EQ(metrics::computeAte(truth, estimate, 0.006).pairs, truth.size());
  EXPECT_THROW(metrics::computeAte(truth, estimate, 0.004), std::runtime_error);
}

TEST(TrajectoryAte, FewerThanThreePairsThrow) {
  const Trajectory truth = curvedTrajectory(40);
  const Trajectory two(truth.begin(), truth.begin() + 2);
  try {
    metrics::computeAte(truth, two);
    FAIL() << "two pairs accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("at least 3"), std::string::npos) << e.what();
  }
  const Trajectory three(truth.begin(), truth.begin() + 3);
  EXPECT_EQ(metrics::computeAte(truth, three).pairs, 3u);
}

TEST(TrajectoryAte, NonFinitePosesAreRefused) {
  const Trajectory truth = curvedTrajectory(10);
  Trajectory estimate = truth;
  estimate[4].pose.translation().y() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(metrics::computeAte(truth, estimate), std::invalid_argument);
  EXPECT_THROW(metrics::computeRpe(truth, estimate), std::invalid_argument);
}

namespace {
/// `truth` with Gaussian noise of `sigma` metres on every coordinate, drawn from `seed`.
Trajectory noisyCopy(const Trajectory& truth, double sigma, unsigned seed) {
  Trajectory estimate = truth;
  std::mt19937 random(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  for (auto& stamped : estimate)
    stamped.pose.translation() += Eigen::Vector3d(noise(random), noise(random), noise(random));
  return estimate;
}
}  // namespace

TEST(TrajectoryAteComparison, TellsAClearlyBetterEstimateFromOneOfTheSameQuality) {
  const Trajectory truth = curvedTrajectory(40);
  const Trajectory precise = moved(noisyCopy(truth, 0.002, 5), rigidMotion(1.0, 0.0, 0.5, 0.2, 0.0, -0.4));
  const Trajectory coarse = noisyCopy(truth, 0.006, 6);
  const metrics::AteComparison clear = metrics::compareAte(truth, precise, coarse);
  EXPECT_EQ(clear.common_poses, truth.size());
  EXPECT_NEAR(clear.first_rmse_m, metrics::computeAte(truth, precise).translation.rmse, 1e-12);
  EXPECT_NEAR(clear.second_rmse_m, metrics::computeAte(truth, coarse).translation.rmse, 1e-12);
  EXPECT_GT(clear.first_lower_fraction, 0.95);
  EXPECT_LT(metrics::compareAte(truth, coarse, precise).first_lower_fraction, 0.05);  // the other way round
  // Two draws of the same noise: neither is better beyond the scatter of 40 poses.
  const metrics::AteComparison same =
      metrics::compareAte(truth, noisyCopy(truth, 0.004, 7), noisyCopy(truth, 0.004, 8));
  EXPECT_GT(same.first_lower_fraction, 0.05);
  EXPECT_LT(same.first_lower_fraction, 0.95);
  EXPECT_LT(std::abs(same.error_correlation), 0.5);  // independent noise
  // An estimate against itself: every resample ties, half each, and the errors correlate fully.
  const metrics::AteComparison itself = metrics::compareAte(truth, precise, precise);
  EXPECT_DOUBLE_EQ(itself.first_lower_fraction, 0.5);
  EXPECT_NEAR(itself.error_correlation, 1.0, 1e-9);
  // Deterministic: the same inputs give the same fraction.
  EXPECT_EQ(metrics::compareAte(truth, precise, coarse).first_lower_fraction, clear.first_lower_fraction);
}

TEST(TrajectoryAteComparison, ComparesOnlyThePosesBothHaveAndRefusesTooFew) {
  const Trajectory truth = curvedTrajectory(40);
  const Trajectory first(truth.begin(), truth.begin() + 30), second(truth.begin() + 20, truth.end());
  EXPECT_EQ(metrics::compareAte(truth, first, second).common_poses, 10u);
  const Trajectory late(truth.begin() + 28, truth.end());
  try {
    metrics::compareAte(truth, first, late);
    FAIL() << "two common poses accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("at least 3"), std::string::npos) << e.what();
  }
  EXPECT_THROW(metrics::compareAte(truth, first, second, 0.02, 0), std::invalid_argument);
}

TEST(TrajectoryRpe, ConstantWorldOffsetHasNoError) {
  const Trajectory truth = curvedTrajectory(100);
  const metrics::RelativePoseError rpe =
      metrics::computeRpe(truth, moved(truth, rigidMotion(1.0, 2.0, 3.0, 0.5, 0.1, -0.3)));
  EXPECT_GT(rpe.pairs, 0u);
  EXPECT_LT(rpe.translation.rmse, 1e-9);
  EXPECT_LT(rpe.rotation_deg.rmse, 1e-6);
}

namespace {
/// Ground truth moving along x at `speed` m/s and turning about z at `turn_rate` rad/s, sampled at 10 Hz.
Trajectory straightRun(std::size_t n, double speed, double turn_rate) {
  Trajectory trajectory;
  for (std::size_t k = 0; k < n; ++k) {
    const double t = 0.1 * static_cast<double>(k);
    trajectory.push_back({50.0 + t, rigidMotion(speed * t, 0.0, 0.0, 0.0, 0.0, turn_rate * t)});
  }
  return trajectory;
}
}  // namespace

TEST(TrajectoryRpe, ScaleDriftGivesItsTranslationPerDelta) {
  // The estimate runs 5 % too far: over 1 s at 0.4 m/s that is 0.02 m, on every pair.
  const Trajectory truth = straightRun(50, 0.4, 0.0);
  const Trajectory estimate = straightRun(50, 0.42, 0.0);
  for (const auto& [delta, unit] :
       {std::pair{1.0, metrics::DeltaUnit::Seconds}, std::pair{10.0, metrics::DeltaUnit::Frames}}) {
    const metrics::RelativePoseError rpe = metrics::computeRpe(truth, estimate, delta, unit);
    // Pairs (i, i + 10) whose partner is not the last pose: i = 0 .. 38.
    EXPECT_EQ(rpe.pairs, 39u);
    EXPECT_NEAR(rpe.translation.rmse, 0.02, 1e-9);
    EXPECT_NEAR(rpe.translation.median, 0.02, 1e-9);
    EXPECT_NEAR(rpe.translation.max, 0.02, 1e-9);
    EXPECT_LT(rpe.rotation_deg.max, 1e-6);
  }
}

TEST(TrajectoryRpe, TurnRateErrorGivesItsAnglePerDelta) {
  // Turning 2 degrees per second too fast: 4 degrees over 2 s.
  const double degree = EIGEN_PI / 180.0;
  const Trajectory truth = straightRun(60, 0.0, 10.0 * degree);
  const Trajectory estimate = straightRun(60, 0.0, 12.0 * degree);
  const metrics::RelativePoseError rpe = metrics::computeRpe(truth, estimate, 2.0);
  EXPECT_EQ(rpe.pairs, 60u - 20u - 1u);
  EXPECT_NEAR(rpe.rotation_deg.rmse, 4.0, 1e-9);
  EXPECT_NEAR(rpe.rotation_deg.mean, 4.0, 1e-9);
  EXPECT_LT(rpe.translation.max, 1e-12);
}

TEST(TrajectoryRpe, PosesWithoutNearbyGroundTruthAreNotCompared) {
  const Trajectory truth = straightRun(50, 0.4, 0.0);  // 50.0 .. 54.9 s
  Trajectory estimate = truth;
  for (auto& stamped : estimate) stamped.timestamp += 2.55;  // 52.55 .. 57.45 s
  // Ground truth is near (within twice its 0.1 s interval) for poses up to
  // 55.05 s, k <= 25; pairs (k, k + 10) need both: k = 0 .. 15.
  EXPECT_EQ(metrics::computeRpe(truth, estimate).pairs, 16u);
  for (auto& stamped : estimate) stamped.timestamp += 10.0;  // after the ground truth ends
  EXPECT_THROW(metrics::computeRpe(truth, estimate), std::runtime_error);
}

TEST(TrajectoryRpe, RefusesBadDeltas) {
  const Trajectory truth = straightRun(50, 0.4, 0.0);
  EXPECT_THROW(metrics::computeRpe(truth, truth, 0.0), std::invalid_argument);
  EXPECT_THROW(metrics::computeRpe(truth, truth, -1.0), std::invalid_argument);
  EXPECT_THROW(metrics::computeRpe(truth, truth, 2.5, metrics::DeltaUnit::Frames), std::invalid_argument);
  EXPECT_THROW(metrics::computeRpe(truth, truth, std::nan("")), std::invalid_argument);
  // Longer than the trajectory: no pair is left.
  EXPECT_THROW(metrics::computeRpe(truth, truth, 100.0), std::runtime_error);
  EXPECT_THROW(metrics::computeRpe(truth, truth, 1e300, metrics::DeltaUnit::Frames), std::runtime_error);
}

TEST(TrajectoryErrorCompatibility, TheOldIoNamesAreTheMetricsFunctions) {
  // Kept for one release after the move out of io (see the header).
  EXPECT_EQ(&io::computeAte, &metrics::computeAte);
  EXPECT_EQ(&io::computeRpe, &metrics::computeRpe);
}
