#pragma once
// Implementation of WeightedCorrespondenceEstimation, included by the library's instantiations
// (or by users, with WEIGHTED_ICP_NO_PRECOMPILE, for other point types).

#include <algorithm>
#include <cmath>
#include <exception>
#include <stdexcept>
#include <thread>
#include <utility>

#include <pcl/console/print.h>

#include "weighted_icp/registration/point_field_weights.h"
#include "weighted_icp/registration/weighted_correspondence_estimation.h"

namespace weighted_icp {

namespace detail {

/// Index (into the candidates, nearest first) of the heaviest candidate within
/// `max_dist_sqr`; ties go to the nearer one. -1 when none is within range.
inline int heaviestCandidate(const NearestNeighborIndex::Scratch& candidates, std::size_t found, double max_dist_sqr,
                             const std::vector<double>& weights) {
  const auto& sq_distances = candidates.squaredDistances();
  if (found == 0 || sq_distances[0] > max_dist_sqr) return -1;
  if (weights.empty()) return 0;  // uniform: the nearest
  const auto& indices = candidates.indices();
  int best = 0;
  double best_weight = weights[indices[0]];
  for (std::size_t j = 1; j < found && sq_distances[j] <= max_dist_sqr; ++j) {
    const double w = weights[indices[j]];
    if (w > best_weight) {
      best = static_cast<int>(j);
      best_weight = w;
    }
  }
  return best;
}

template <typename PointT>
bool loadXyz(const PointT& p, float* xyz) {
  xyz[0] = p.x;
  xyz[1] = p.y;
  xyz[2] = p.z;
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
}

/// Candidates a search can return: never more than the indexed points, so an
/// absurd k costs no more memory than k = the index size (same results).
inline std::size_t scratchSize(unsigned int k, const NearestNeighborIndex& index) {
  return std::max<std::size_t>(1, std::min<std::size_t>(k, index.size()));
}

/// Source points per chunk of the parallel loop: small enough that a thread the machine preempts in the
/// middle of a chunk holds up little of the loop (256 was measured slower at 2 threads on a loaded machine),
/// large enough that claiming a chunk (a mutex) costs nothing in comparison.
constexpr std::size_t kChunk = 64;
/// Loops this short run on one thread: waking a thread costs more than it saves.
constexpr std::size_t kMinParallel = 512;

/// Threads for a loop of `n` queries: `requested` (0: every hardware thread), one for short loops, where
/// waking a thread costs more than it saves.
inline unsigned threadsFor(unsigned int requested, std::size_t n) {
  if (n <= kMinParallel) return 1;
  if (requested > 0) return requested;
  const unsigned int hardware = std::thread::hardware_concurrency();
  return hardware > 0 ? hardware : 1;
}

/// Weights for `cloud`: the explicit vector if set (size checked), else the
/// named field, else uniform (empty). False, with `error` set, when unusable.
template <typename PointT>
bool resolveWeights(const pcl::PointCloud<PointT>& cloud, const std::vector<double>& explicit_weights,
                    const std::string& field_name, const char* default_field, std::vector<double>& weights,
                    std::string& error) {
  if (!explicit_weights.empty()) {
    if (explicit_weights.size() != cloud.size()) {
      error = std::to_string(explicit_weights.size()) + " weights given for a cloud of " +
              std::to_string(cloud.size()) + " points";
      return false;
    }
    weights = explicit_weights;
    return true;
  }
  auto from_field = readWeightField(cloud, field_name);
  if (!from_field) {
    weights.clear();
    if (field_name == default_field) return true;
    error = "the point type has no field '" + field_name + "'";
    return false;
  }
  try {
    checkWeights(*from_field, "field '" + field_name + "'");
  } catch (const std::invalid_argument& e) {
    error = e.what();
    return false;
  }
  weights = std::move(*from_field);
  return true;
}

}  // namespace detail

template <typename PointSource, typename PointTarget, typename Scalar>
WeightedCorrespondenceEstimation<PointSource, PointTarget, Scalar>::WeightedCorrespondenceEstimation(unsigned int k) {
  corr_name_ = "WeightedCorrespondenceEstimation";
  setNumberOfNeighbors(k);
}

template <typename PointSource, typename PointTarget, typename Scalar>
void WeightedCorrespondenceEstimation<PointSource, PointTarget, Scalar>::setNumberOfNeighbors(unsigned int k) {
  if (k == 0) throw std::invalid_argument(getClassName() + ": the number of neighbours must be >= 1");
  k_ = k;
}

template <typename PointSource, typename PointTarget, typename Scalar>
void WeightedCorrespondenceEstimation<PointSource, PointTarget, Scalar>::setNumberOfThreads(unsigned int threads) {
  // ~100,000 threads exhaust the process; far fewer already only thrash.
  if (threads > kMaxThreads)
    throw std::invalid_argument(getClassName() + ": " + std::to_string(threads) + " threads requested, at most " +
                                std::to_string(kMaxThreads) + " (0 = every hardware thread)");
  threads_ = threads;
}

template <typename PointSource, typename PointTarget, typename Scalar>
void WeightedCorrespondenceEstimation<PointSource, PointTarget, Scalar>::setCandidateReuse(bool reuse) {
  reuse_candidates_ = reuse;
  cache_.reset(0);
}

template <typename PointSource, typename PointTarget, typename Scalar>
std::size_t WeightedCorrespondenceEstimation<PointSource, PointTarget, Scalar>::getLastSearchedCount() const {
  return reuse_candidates_ ? cache_.count(CandidateCache::Action::kSearched) : (indices_ ? indices_->size() : 0);
}

template <typename PointSource, typename PointTarget, typename Scalar>
std::size_t WeightedCorrespondenceEstimation<PointSource, PointTarget, Scalar>::getLastReusedCount() const {
  return reuse_candidates_ ? cache_.count(CandidateCache::Action::kReused) : 0;
}

template <typename PointSource, typename PointTarget, typename Scalar>
void WeightedCorrespondenceEstimation<PointSource, PointTarget, Scalar>::setTargetWeights(std::vector<double> weights) {
  checkWeights(weights, getClassName() + "::setTargetWeights");
  target_weights_ = std::move(weights);
  target_cloud_updated_ = true;
}

template <typename PointSource, typename PointTarget, typename Scalar>
void WeightedCorrespondenceEstimation<PointSource, PointTarget, Scalar>::setTargetWeightField(
    const std::string& field_name) {
  target_weight_field_ = field_name;
  target_cloud_updated_ = true;
}

template <typename PointSource, typename PointTarget, typename Scalar>
void WeightedCorrespondenceEstimation<PointSource, PointTarget, Scalar>::setSourceWeights(std::vector<double> weights) {
  checkWeights(weights, getClassName() + "::setSourceWeights");
  source_weights_ = std::move(weights);
  source_cloud_updated_ = true;
}

template <typename PointSource, typename PointTarget, typename Scalar>
void WeightedCorrespondenceEstimation<PointSource, PointTarget, Scalar>::setSourceWeightField(
    const std::string& field_name) {
  source_weight_field_ = field_name;
  source_cloud_updated_ = true;
}

template <typename PointSource, typename PointTarget, typename Scalar>
void WeightedCorrespondenceEstimation<PointSource, PointTarget, Scalar>::setPointRepresentation(
    const typename Base::PointRepresentationConstPtr& point_representation) {
  PCL_WARN("[pcl::registration::%s::setPointRepresentation] This class does not use a point representation\n",
           getClassName().c_str());
  Base::setPointRepresentation(point_representation);
}

template <typename PointSource, typename PointTarget, typename Scalar>
void WeightedCorrespondenceEstimation<PointSource, PointTarget, Scalar>::setSearchMethodSource(
    const typename Base::KdTreeReciprocalPtr& tree, bool force_no_recompute) {
  PCL_WARN("[pcl::registration::%s::setSearchMethodSource] This class does not use a source search method\n",
           getClassName().c_str());
  Base::setSearchMethodSource(tree, force_no_recompute);
}

template <typename PointSource, typename PointTarget, typename Scalar>
template <typename PointT>
bool WeightedCorrespondenceEstimation<PointSource, PointTarget, Scalar>::buildIndex(
    NearestNeighborIndex& index, const pcl::PointCloud<PointT>& cloud, const pcl::Indices* indices, const char* what) {
  try {
    return index.build(cloud, indices);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(getClassName() + ": " + what + " " + e.what());
  }
}

template <typename PointSource, typename PointTarget, typename Scalar>
bool WeightedCorrespondenceEstimation<PointSource, PointTarget, Scalar>::initComputeWeighted() {
  if (!target_) {
    PCL_ERROR("[weighted_icp::%s::compute] No input target dataset was given!\n", getClassName().c_str());
    return false;
  }
  if (!pcl::PCLBase<PointSource>::initCompute()) return false;
  if (target_cloud_updated_) {
    // The cache holds rows of the index: a new index invalidates it (an unchanged target keeps both).
    if (buildIndex(target_index_, *target_, target_indices_.get(), "target")) cache_.reset(0);
    std::string error;
    if (!detail::resolveWeights(*target_, target_weights_, target_weight_field_, kDefaultWeightField,
                                target_weights_in_use_, error)) {
      PCL_ERROR("[weighted_icp::%s::compute] Target weights: %s.\n", getClassName().c_str(), error.c_str());
      return false;
    }
    target_cloud_updated_ = false;
  }
  if (target_index_.empty()) {
    PCL_ERROR("[weighted_icp::%s::compute] The target has no finite point to match.\n", getClassName().c_str());
    return false;
  }
  return true;
}

template <typename PointSource, typename PointTarget, typename Scalar>
bool WeightedCorrespondenceEstimation<PointSource, PointTarget, Scalar>::initComputeWeightedReciprocal() {
  if (source_cloud_updated_) {
    buildIndex(source_index_, *input_, indices_.get(), "source");
    std::string error;
    if (!detail::resolveWeights(*input_, source_weights_, source_weight_field_, kDefaultWeightField,
                                source_weights_in_use_, error)) {
      PCL_ERROR("[weighted_icp::%s::compute] Source weights: %s.\n", getClassName().c_str(), error.c_str());
      return false;
    }
    source_cloud_updated_ = false;
  }
  return true;
}

template <typename PointSource, typename PointTarget, typename Scalar>
void WeightedCorrespondenceEstimation<PointSource, PointTarget, Scalar>::chooseTargets(
    double max_dist_sqr, pcl::Correspondences& per_source) {
  const std::size_t n = indices_->size();
  per_source.resize(n);
  const unsigned threads = detail::threadsFor(threads_, n);
  // One scratch per thread, made before the loop so that an allocation failure is thrown here.
  const std::size_t scratch_size = detail::scratchSize(k_, target_index_);
  if (reuse_candidates_) cache_.resize(n, scratch_size);
  std::vector<NearestNeighborIndex::Scratch> scratches(threads, NearestNeighborIndex::Scratch(scratch_size));
  std::vector<CandidateCache::Work> works(threads, cache_.makeWork());
  // Each source point is decided on its own and written to its own slot (and
  // cache entry), so the result cannot depend on how the loop is split.
  pool_.run(n, detail::kChunk, threads, [&](std::size_t begin, std::size_t end, unsigned worker) {
    NearestNeighborIndex::Scratch& candidates = scratches[worker];
    for (std::size_t i = begin; i < end; ++i) {
      pcl::Correspondence& corr = per_source[i];
      corr.index_query = (*indices_)[i];
      corr.index_match = pcl::UNAVAILABLE;
      float query[3];
      if (!detail::loadXyz((*input_)[corr.index_query], query)) continue;
      const std::size_t found = reuse_candidates_ ? cache_.knn(i, query, target_index_, works[worker], candidates)
                                                  : target_index_.knn(query, candidates);
      const int best = detail::heaviestCandidate(candidates, found, max_dist_sqr, target_weights_in_use_);
      if (best < 0) continue;
      corr.index_match = candidates.indices()[best];
      corr.distance = candidates.squaredDistances()[best];
    }
  });
}

namespace detail {
/// Drops the unmatched slots, keeping the order of the source indices.
inline void keepMatched(pcl::Correspondences& correspondences) {
  std::size_t kept = 0;
  for (const auto& corr : correspondences)
    if (corr.index_match != pcl::UNAVAILABLE) correspondences[kept++] = corr;
  correspondences.resize(kept);
}
}  // namespace detail

template <typename PointSource, typename PointTarget, typename Scalar>
void WeightedCorrespondenceEstimation<PointSource, PointTarget, Scalar>::determineCorrespondences(
    pcl::Correspondences& correspondences, double max_distance) {
  if (!initComputeWeighted()) {
    correspondences.clear();
    return;
  }
  chooseTargets(max_distance * max_distance, correspondences);
  detail::keepMatched(correspondences);
  this->deinitCompute();
}

template <typename PointSource, typename PointTarget, typename Scalar>
void WeightedCorrespondenceEstimation<PointSource, PointTarget, Scalar>::determineReciprocalCorrespondences(
    pcl::Correspondences& correspondences, double max_distance) {
  if (!initComputeWeighted() || !initComputeWeightedReciprocal()) {
    correspondences.clear();
    return;
  }
  const double max_dist_sqr = max_distance * max_distance;
  chooseTargets(max_dist_sqr, correspondences);
  const std::size_t n = correspondences.size();
  const unsigned threads = detail::threadsFor(threads_, n);
  const std::size_t scratch_size = detail::scratchSize(k_, source_index_);
  std::vector<NearestNeighborIndex::Scratch> scratches(threads, NearestNeighborIndex::Scratch(scratch_size));
  pool_.run(n, detail::kChunk, threads, [&](std::size_t begin, std::size_t end, unsigned worker) {
    NearestNeighborIndex::Scratch& candidates = scratches[worker];
    for (std::size_t i = begin; i < end; ++i) {
      pcl::Correspondence& corr = correspondences[i];
      if (corr.index_match == pcl::UNAVAILABLE) continue;
      float query[3];
      detail::loadXyz((*target_)[corr.index_match], query);  // finite: it is in the index
      const std::size_t found = source_index_.knn(query, candidates);
      const int back = detail::heaviestCandidate(candidates, found, max_dist_sqr, source_weights_in_use_);
      if (back < 0 || candidates.indices()[back] != corr.index_query) corr.index_match = pcl::UNAVAILABLE;
    }
  });
  detail::keepMatched(correspondences);
  this->deinitCompute();
}

template <typename PointSource, typename PointTarget, typename Scalar>
typename WeightedCorrespondenceEstimation<PointSource, PointTarget, Scalar>::Base::Ptr
WeightedCorrespondenceEstimation<PointSource, PointTarget, Scalar>::clone() const {
  return std::make_shared<WeightedCorrespondenceEstimation<PointSource, PointTarget, Scalar>>(*this);
}

}  // namespace weighted_icp

#define WEIGHTED_ICP_INSTANTIATE_WeightedCorrespondenceEstimation(PointSource, PointTarget, Scalar) \
  template class weighted_icp::WeightedCorrespondenceEstimation<PointSource, PointTarget, Scalar>;
