#pragma once
// Confidence-weighted correspondence estimation, a drop-in for
// pcl::registration::CorrespondenceEstimation:
//
//   auto ce = weighted_icp::WeightedCorrespondenceEstimation<P, P>::Ptr(...);
//   ce->setNumberOfNeighbors(5);
//   ce->setTargetWeights(weights);   // or a "weight" field of the target points
//   icp.setCorrespondenceEstimation(ce);
//
// Rule: for each source point take its k nearest target points within the
// maximum correspondence distance and choose the one with the largest target
// weight; equal weights go to the nearer point. With k = 1 (or uniform
// weights) it is exactly PCL's nearest-neighbour rule, with the same results.
// Weights rank candidates, they do not gate them: a source point whose
// candidates all weigh 0 still gets the nearest (the paper's code drops it);
// gate with the maximum distance or a correspondence rejector.
//
// Unlike PCL's class it builds its target index once per target (re-setting
// an unchanged target, as IterativeClosestPoint does on every align(), costs a
// comparison, not a rebuild), reuses each source point's candidates from one
// ICP iteration to the next while the point stays within their margin
// (CandidateCache: exact, the same correspondences bit for bit), searches in
// parallel (WorkerPool) with results independent of the thread count, and
// allocates nothing per point. It keeps its own index,
// so the tree given by setSearchMethodTarget() is not used.
//
// Nor are a point representation or a source search tree: setPointRepresentation()
// and setSearchMethodSource() print a PCL_WARN saying so (as PCL's
// setSourceNormals() does where normals are not needed), then store the value
// as the base class would. PCL declares them non-virtual, so this class hides
// them: only calls on this type warn; calls through a
// CorrespondenceEstimationBase pointer (IterativeClosestPoint passes its
// search trees that way on every align()) are not intercepted.

#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <pcl/correspondence.h>
#include <pcl/registration/correspondence_estimation.h>

#include "weighted_icp/registration/candidate_cache.h"
#include "weighted_icp/registration/nearest_neighbor_index.h"
#include "weighted_icp/registration/worker_pool.h"

namespace weighted_icp {

template <typename PointSource, typename PointTarget, typename Scalar = float>
class WeightedCorrespondenceEstimation
    : public pcl::registration::CorrespondenceEstimationBase<PointSource, PointTarget, Scalar> {
 public:
  using Ptr = std::shared_ptr<WeightedCorrespondenceEstimation<PointSource, PointTarget, Scalar>>;
  using ConstPtr = std::shared_ptr<const WeightedCorrespondenceEstimation<PointSource, PointTarget, Scalar>>;
  using Base = pcl::registration::CorrespondenceEstimationBase<PointSource, PointTarget, Scalar>;

  using Base::getClassName;

  /// Name of the point field read as weight when no weight vector is given.
  static constexpr const char* kDefaultWeightField = "weight";

  explicit WeightedCorrespondenceEstimation(unsigned int k = 5);

  /// Number of nearest target points among which the heaviest is chosen (>= 1).
  void setNumberOfNeighbors(unsigned int k);
  unsigned int getNumberOfNeighbors() const { return k_; }

  /// One weight per target point (finite, >= 0), by cloud index. Takes
  /// precedence over the weight field. The size is checked against the target
  /// when correspondences are computed. Throws std::invalid_argument naming the
  /// first bad weight.
  void setTargetWeights(std::vector<double> weights);
  const std::vector<double>& getTargetWeights() const { return target_weights_; }
  /// Reads target weights from this point field when no vector is set (default
  /// "weight"). A point type without that field gets uniform weights.
  void setTargetWeightField(const std::string& field_name);
  const std::string& getTargetWeightField() const { return target_weight_field_; }

  /// The same for the source points, used by the reciprocal rule only.
  void setSourceWeights(std::vector<double> weights);
  const std::vector<double>& getSourceWeights() const { return source_weights_; }
  void setSourceWeightField(const std::string& field_name);
  const std::string& getSourceWeightField() const { return source_weight_field_; }

  /// @brief Not used (distances are always plain xyz): warns, then stores the value as the base class does.
  /// Hides the non-virtual base method, so calls through a base pointer do not warn.
  /// @param point_representation  ignored by the search
  void setPointRepresentation(const typename Base::PointRepresentationConstPtr& point_representation);

  /// @brief Not used (the reciprocal rule builds its own source index): warns, then stores the tree as the
  /// base class does. Hides the non-virtual base method, so calls through a base pointer do not warn.
  /// @param tree                ignored by the search
  /// @param force_no_recompute  stored with the tree, also unused
  void setSearchMethodSource(const typename Base::KdTreeReciprocalPtr& tree, bool force_no_recompute = false);

  /// Most search threads setNumberOfThreads() accepts.
  static constexpr unsigned int kMaxThreads = 1024;

  /// @brief Threads for the search; 0 (default) uses every hardware thread.
  /// @param threads  0 to kMaxThreads; larger counts are refused (std::invalid_argument), not clamped, so a
  ///                 wrapped-around negative number is reported instead of silently running
  void setNumberOfThreads(unsigned int threads);
  unsigned int getNumberOfThreads() const { return threads_; }

  /// @brief Whether the search reuses each source point's candidates across calls while the point moves
  /// less than their margin (CandidateCache). On by default: the correspondences are bit-identical either
  /// way; off, every call searches the index for every point.
  /// @param reuse  true to reuse
  void setCandidateReuse(bool reuse);
  bool getCandidateReuse() const { return reuse_candidates_; }
  /// @brief Source points the last determineCorrespondences() searched in the index.
  std::size_t getLastSearchedCount() const;
  /// @brief Source points the last determineCorrespondences() answered from reused candidates.
  std::size_t getLastReusedCount() const;
  /// @brief Candidates the reuse holds in all (memory: 4 bytes each).
  std::size_t getCandidateCount() const { return cache_.candidateCount(); }

  /// Throws std::invalid_argument naming the point when a finite target point has a coordinate beyond
  /// NearestNeighborIndex::kMaxCoordinate (the float index would overflow), checked once per target.
  void determineCorrespondences(pcl::Correspondences& correspondences,
                                double max_distance = std::numeric_limits<double>::max()) override;

  /// Keeps a pair (s, t) only if the same rule applied from t, among the k
  /// nearest source points weighted by the source weights, chooses s.
  void determineReciprocalCorrespondences(pcl::Correspondences& correspondences,
                                          double max_distance = std::numeric_limits<double>::max()) override;

  typename Base::Ptr clone() const override;

 protected:
  using Base::corr_name_;
  using Base::indices_;
  using Base::input_;
  using Base::source_cloud_updated_;
  using Base::target_;
  using Base::target_cloud_updated_;
  using Base::target_indices_;

 private:
  /// Builds what the search needs (indices, target index and weights); false,
  /// with a PCL_ERROR saying why, when it cannot run.
  bool initComputeWeighted();
  bool initComputeWeightedReciprocal();
  /// For every source index, the chosen target (or UNAVAILABLE) and its
  /// squared distance, written by slot so the thread count cannot matter.
  void chooseTargets(double max_dist_sqr, pcl::Correspondences& per_source);
  /// Builds `index` on `cloud` (true when it changed); a coordinate the index cannot hold is thrown as
  /// std::invalid_argument naming `what` ("target"/"source") and the point.
  template <typename PointT>
  bool buildIndex(NearestNeighborIndex& index, const pcl::PointCloud<PointT>& cloud, const pcl::Indices* indices,
                  const char* what);

  unsigned int k_;
  unsigned int threads_ = 0;
  std::vector<double> target_weights_;
  std::vector<double> source_weights_;
  std::string target_weight_field_ = kDefaultWeightField;
  std::string source_weight_field_ = kDefaultWeightField;

  bool reuse_candidates_ = true;
  NearestNeighborIndex target_index_;
  CandidateCache cache_;  // per source slot, rows of target_index_
  WorkerPool pool_;       // a clone starts its own threads
  NearestNeighborIndex source_index_;
  std::vector<double> target_weights_in_use_;  // empty means uniform
  std::vector<double> source_weights_in_use_;
};

}  // namespace weighted_icp

// The library instantiates the class for pcl::PointXYZ, PointXYZI, PointNormal
// and LandmarkPoint with Scalar float and double; for other point types
// include the implementation, as PCL does for its own templates.
#if defined(PCL_NO_PRECOMPILE) || defined(WEIGHTED_ICP_NO_PRECOMPILE)
#include "weighted_icp/registration/impl/weighted_correspondence_estimation.hpp"
#endif
