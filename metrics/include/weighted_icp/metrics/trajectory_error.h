#pragma once
// Trajectory errors as the TUM RGB-D benchmark's tools compute them:
// evaluate_ate.py (absolute trajectory error after rigid alignment) and
// evaluate_rpe.py --fixed_delta (relative pose error).

#include <cstddef>

#include <Eigen/Geometry>

#include "weighted_icp/core/statistics.h"
#include "weighted_icp/io/trajectory.h"

namespace weighted_icp::metrics {

/// @brief The absolute trajectory error and the alignment it was measured after.
struct AbsoluteTrajectoryError {
  std::size_t pairs = 0;        // associated (ground truth, estimate) poses
  ErrorStatistics translation;  // metres, after alignment
  /// The rigid motion (no scale) that best maps the estimated positions onto
  /// the ground-truth ones: ground truth ≈ alignment * estimate.
  Eigen::Isometry3d alignment = Eigen::Isometry3d::Identity();
};

/// @brief evaluate_ate.py: associates by timestamp (as io::associate), aligns
/// the estimated positions onto ground truth (Horn/Umeyama, no scale) and
/// measures the remaining position errors. Throws std::runtime_error when
/// fewer than 3 pairs associate, std::invalid_argument for non-finite poses.
/// @param groundtruth camera-to-world poses
/// @param estimate camera-to-world poses, in any frame
/// @param max_difference pair poses whose timestamps differ by less than this, seconds
AbsoluteTrajectoryError computeAte(const io::Trajectory& groundtruth, const io::Trajectory& estimate,
                                   double max_difference = 0.02);

/// @brief Two estimates of one sequence compared pose by pose, to tell a real difference from the scatter of a
/// short sequence: over the ground-truth poses both are paired with (each estimate aligned on its own, as computeAte
/// does), how often the first has the lower RMSE when those poses are resampled with replacement, in runs of
/// consecutive poses as trajectory errors drift (a paired moving-block bootstrap, blocks of n^(1/3) poses).
struct AteComparison {
  AbsoluteTrajectoryError first, second;           // each over all its pairs, as computeAte
  std::size_t common_poses = 0;                    // ground-truth poses paired with both
  double first_rmse_m = 0.0, second_rmse_m = 0.0;  // over the common poses
  /// Pearson correlation of the two per-pose errors: near 1, both share most of their error (ground truth, hard
  /// frames).
  double error_correlation = 0.0;
  std::size_t resamples = 0;
  /// Fraction of resamples in which the first's RMSE is the lower: near 0.5, no difference the poses can show;
  /// above 0.95 (below 0.05), the first (the second) is better beyond the scatter.
  double first_lower_fraction = 0.0;
};

/// @brief Compares two estimates' absolute trajectory errors on the same ground truth (AteComparison), with a
/// deterministic bootstrap. Throws as computeAte for either estimate, std::runtime_error when fewer than 3
/// ground-truth poses are paired with both, std::invalid_argument for 0 resamples.
/// @param groundtruth camera-to-world poses
/// @param first an estimate, in any frame
/// @param second another estimate of the same frames, in any frame
/// @param max_difference as for computeAte
/// @param resamples bootstrap resamples
AteComparison compareAte(const io::Trajectory& groundtruth, const io::Trajectory& first, const io::Trajectory& second,
                         double max_difference = 0.02, std::size_t resamples = 2000);

/// @brief How the RPE's delta is counted.
enum class DeltaUnit { Seconds, Frames };

/// @brief The relative pose error over pose pairs a fixed delta apart.
struct RelativePoseError {
  std::size_t pairs = 0;         // compared pose pairs (i, j)
  ErrorStatistics translation;   // metres
  ErrorStatistics rotation_deg;  // degrees
};

/// @brief evaluate_rpe.py --fixed_delta: for each estimated pose i (by time),
/// j is the pose nearest to i + delta (seconds, or frames); as that script,
/// pairs whose j is the last pose are skipped (it cannot tell "last" from
/// "past the end"). Each estimated pose is compared with the ground-truth pose
/// nearest in time, if within twice the median ground-truth interval. The
/// error of a pair is (E_j^-1 E_i)^-1 (G_j^-1 G_i). Throws std::runtime_error
/// when fewer than 2 pairs remain, std::invalid_argument for a delta that is
/// not > 0 (or not a whole number of frames) and for non-finite poses.
/// @param groundtruth camera-to-world poses
/// @param estimate camera-to-world poses
/// @param delta the distance between the poses of a pair
/// @param unit what delta counts
RelativePoseError computeRpe(const io::Trajectory& groundtruth, const io::Trajectory& estimate, double delta = 1.0,
                             DeltaUnit unit = DeltaUnit::Seconds);

}  // namespace weighted_icp::metrics

namespace weighted_icp::io {
// These lived in io/trajectory.h before 0.2; the names keep old code compiling
// for one release once it includes this header and links weighted_icp::metrics.
using metrics::AbsoluteTrajectoryError;
using metrics::computeAte;
using metrics::computeRpe;
using metrics::DeltaUnit;
using metrics::RelativePoseError;
using weighted_icp::ErrorStatistics;
}  // namespace weighted_icp::io
