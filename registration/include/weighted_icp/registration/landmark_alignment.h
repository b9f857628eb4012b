#pragma once
// The alignment pipeline: PCL's ICP with the weighted correspondence rule,
// then, on request, a refinement stage with nearest-neighbour correspondences.
//
// The weighted rule widens the basin of convergence but biases the optimum
// (it prefers heavy points to the true neighbour); refinement starts from the
// weighted result and finishes with k = 1, keeping the basin without the bias.

#include <cmath>
#include <cstddef>
#include <limits>
#include <memory>

#include <Eigen/Core>

#include "weighted_icp/registration/landmark_map.h"
#include "weighted_icp/registration/landmark_point.h"
#include "weighted_icp/registration/weight_strategies.h"

namespace weighted_icp {

struct AlignmentSettings {
  /// Neighbours among which the heaviest is chosen; 1 is plain ICP.
  unsigned int k = 5;
  int max_iterations = 150;  // the paper's value
  /// PCL's default: no limit.
  double max_correspondence_distance = std::sqrt(std::numeric_limits<double>::max());
  /// PCL's convergence defaults (DefaultConvergenceCriteria) otherwise.
  double transformation_epsilon = 0.0;
  double euclidean_fitness_epsilon = -std::numeric_limits<double>::max();
  bool refine = false;
  int refine_max_iterations = 150;
  unsigned int threads = 0;  // 0: every hardware thread
};

struct AlignmentResult {
  /// Maps the source (as given) onto the target.
  Eigen::Matrix4d transformation = Eigen::Matrix4d::Identity();
  /// PCL's fitness score: mean squared distance from each transformed source
  /// point to its nearest target point, unweighted.
  double fitness_score = 0.0;
  int iterations = 0;               // weighted stage
  int refine_iterations = 0;        // refinement stage, 0 when not run
  bool converged = false;           // of the last stage run
  std::size_t correspondences = 0;  // used by the last iteration
  double time_ms = 0.0;
};

/// Aligns weighted landmark clouds (weights in the points' `weight` field).
/// Holds the target: its search structures are built once, in setTarget(),
/// and shared by every align() call.
class LandmarkAligner {
 public:
  explicit LandmarkAligner(AlignmentSettings settings = {});
  ~LandmarkAligner();
  LandmarkAligner(LandmarkAligner&&) noexcept;
  LandmarkAligner& operator=(LandmarkAligner&&) noexcept;

  const AlignmentSettings& settings() const { return settings_; }

  /// Throws std::invalid_argument when the cloud is empty or has no finite point.
  void setTarget(LandmarkCloud::ConstPtr target);
  /// Throws std::invalid_argument when the source is empty or has no finite
  /// point, or when no target was set.
  AlignmentResult align(const LandmarkCloud::ConstPtr& source,
                        const Eigen::Matrix4d& guess = Eigen::Matrix4d::Identity());

 private:
  struct Pipeline;
  AlignmentSettings settings_;
  std::unique_ptr<Pipeline> pipeline_;
};

/// Aligns two landmark maps with one weight strategy: a one-off convenience
/// around LandmarkAligner.
AlignmentResult alignLandmarkMaps(const LandmarkMap& source, const LandmarkMap& target, const WeightFunction& weight,
                                  const AlignmentSettings& settings,
                                  const Eigen::Matrix4d& guess = Eigen::Matrix4d::Identity());

}  // namespace weighted_icp
