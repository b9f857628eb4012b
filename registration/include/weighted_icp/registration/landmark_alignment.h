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
#include <string>

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
  /// Stop a stage when its correspondences are the same pairs as in the previous iteration (the pose can
  /// only repeat then; see correspondence_repeat_criteria.h), and let refinement stop at its first
  /// iteration when k = 1 finds the weighted stage's last pairs. Off: PCL's criteria alone.
  bool stop_on_repeated_correspondences = true;
  bool refine = false;
  int refine_max_iterations = 150;
  unsigned int threads = 0;  // 0: every hardware thread, at most 1024
};

struct AlignmentResult {
  /// Maps the source (as given) onto the target.
  Eigen::Matrix4d transformation = Eigen::Matrix4d::Identity();
  /// PCL's fitness score: mean squared distance from each transformed source
  /// point to its nearest target point, unweighted. NaN when degenerate.
  double fitness_score = 0.0;
  int iterations = 0;         // weighted stage
  int refine_iterations = 0;  // refinement stage, 0 when not run
  bool converged = false;     // of the last stage run (PCL's hasConverged(): true at the iteration limit too)
  /// The last stage stopped because it reached its iteration limit, not because its criteria (transformation,
  /// fitness, repeated correspondences) were met; PCL still reports that as converged. A caller that needs a
  /// settled pose tests converged && !stopped_at_iteration_limit (wicp_align's exit 3 does).
  bool stopped_at_iteration_limit = false;
  std::size_t correspondences = 0;  // used by the last iteration
  double time_ms = 0.0;
  /// The problem has no unique rigid solution, so ICP was not run (the
  /// transformation is the guess, converged false): fewer than 3 finite points,
  /// all identical or all collinear in source or target, or k > 1 and at least
  /// the target's finite point count (every source point would choose among
  /// the whole target). `reason` says which, naming the cloud.
  bool degenerate = false;
  std::string reason;
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

  /// @brief Sets the target and builds its search structures, once.
  /// @param target  throws std::invalid_argument when it is empty, has no finite point, or a finite point has a
  ///                coordinate beyond NearestNeighborIndex::kMaxCoordinate (named by index)
  void setTarget(LandmarkCloud::ConstPtr target);
  /// @brief Aligns `source` onto the target; a degenerate problem is reported in the result, not run.
  /// @param source  throws std::invalid_argument as setTarget() does, or when no target was set
  /// @param guess   initial transformation

  AlignmentResult align(const LandmarkCloud::ConstPtr& source,
                        const Eigen::Matrix4d& guess = Eigen::Matrix4d::Identity());

 private:
  struct Pipeline;
  /// Why aligning `source` onto the current target is degenerate; empty when it is not.
  std::string degeneracy(const LandmarkCloud& source, std::size_t source_points) const;
  AlignmentSettings settings_;
  std::unique_ptr<Pipeline> pipeline_;
};

/// Aligns two landmark maps with one weight strategy: a one-off convenience
/// around LandmarkAligner.
AlignmentResult alignLandmarkMaps(const LandmarkMap& source, const LandmarkMap& target, const WeightFunction& weight,
                                  const AlignmentSettings& settings,
                                  const Eigen::Matrix4d& guess = Eigen::Matrix4d::Identity());

}  // namespace weighted_icp
