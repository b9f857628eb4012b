#pragma once
// A convergence criterion for PCL's ICP that also stops when an iteration's correspondences are the same
// pairs as the previous iteration's.
//
// Why it is free: ICP estimates each increment from the pairs alone (PCL's SVD estimation reads only their
// indices and the current points). Iteration i estimated T_i as the best motion for its pairs C_i. If
// C_{i+1} = C_i, iteration i+1 solves the same problem from points already moved by T_i, so in exact
// arithmetic its increment is the identity and the next pose is T_i again; the pairs found from that pose
// are then C_i once more, and so on. Running on only repeats the same estimate until PCL's own tests notice:
// its increments are then at the level of float rounding (PCL's ICP stores the moved source points in the
// point type, float, and re-rounds them every iteration: measured on the real map, the poses of runs with
// and without this rule differ by up to 3.6e-7 in a matrix entry on its halves, 1.9e-6 on the whole map
// where the run without it repeats 78 more iterations; the drift grows with the repeats). So stopping on a repeat keeps
// the final transformation (to that rounding) and saves the iterations that would only confirm it.
//
// The pairs compared are those ICP estimates from (after the correspondence rejectors): index_query and
// index_match. Not the distance (it changes with the pose; pcl::Correspondence's weight shares its storage),
// so the rule is exact for an estimation that reads only the pairs' indices and the points, as PCL's SVD
// estimation (ICP's default) does; not for one that weights pairs by their distance.

#include <cstddef>
#include <memory>

#include <pcl/correspondence.h>
#include <pcl/registration/default_convergence_criteria.h>

namespace weighted_icp {

/// @brief PCL's DefaultConvergenceCriteria plus "stop when the pairs repeat" (see the file comment).
/// Install it in a subclass of pcl::IterativeClosestPoint (its convergence_criteria_ is protected):
/// `convergence_criteria_ = std::make_shared<CorrespondenceRepeatCriteria<Scalar>>(nr_iterations_,
/// transformation_, *correspondences_);`
template <typename Scalar = float>
class CorrespondenceRepeatCriteria : public pcl::registration::DefaultConvergenceCriteria<Scalar> {
 public:
  using Ptr = std::shared_ptr<CorrespondenceRepeatCriteria<Scalar>>;
  using ConstPtr = std::shared_ptr<const CorrespondenceRepeatCriteria<Scalar>>;
  using Base = pcl::registration::DefaultConvergenceCriteria<Scalar>;

  /// @brief Watches the same members DefaultConvergenceCriteria does.
  /// @param iterations       the ICP's iteration counter (reset to 0 by each align())
  /// @param transform        the ICP's last increment
  /// @param correspondences  the pairs the ICP estimated the increment from
  CorrespondenceRepeatCriteria(const int& iterations, const typename Base::Matrix4& transform,
                               const pcl::Correspondences& correspondences)
      : Base(iterations, transform, correspondences) {}

  /// @brief Turns the repeat test on or off (on by default); off, this is DefaultConvergenceCriteria.
  /// @param enabled  true to stop on repeated pairs
  void setStopOnRepeat(bool enabled) { enabled_ = enabled; }
  /// @brief Whether the repeat test is on.
  bool getStopOnRepeat() const { return enabled_; }

  /// @brief Keeps the pairs of the last iteration across the next align() call, so that its first
  /// iteration may already stop (LandmarkAligner's refinement stage starts where the weighted stage
  /// ended: if k = 1 gives the weighted stage's last pairs, the pose is already their optimum).
  void carryOverToNextRun() { carry_over_ = true; }

  /// @brief True when the last run stopped because its pairs repeated.
  bool stoppedOnRepeat() const { return stopped_on_repeat_; }

  /// @brief PCL's tests first (they keep their bookkeeping), then the repeat test.
  bool hasConverged() override {
    if (this->iterations_ <= 1) {
      stopped_on_repeat_ = false;
      if (!carry_over_) previous_.clear();
      carry_over_ = false;
    }
    const bool repeated = enabled_ && !previous_.empty() && samePairs(previous_, this->correspondences_);
    previous_ = this->correspondences_;
    if (Base::hasConverged()) return true;
    if (!repeated) return false;
    // PCL has no state for this; TRANSFORM says what it means: the transformation no longer changes.
    this->convergence_state_ = Base::CONVERGENCE_CRITERIA_TRANSFORM;
    stopped_on_repeat_ = true;
    return true;
  }

 private:
  static bool samePairs(const pcl::Correspondences& a, const pcl::Correspondences& b) {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i)
      if (a[i].index_query != b[i].index_query || a[i].index_match != b[i].index_match) return false;
    return true;
  }

  bool enabled_ = true;
  bool carry_over_ = false;
  bool stopped_on_repeat_ = false;
  pcl::Correspondences previous_;
};

}  // namespace weighted_icp
