// NearestNeighborIndex: BucketKdTree for the search, FLANN (PCL's tree) for the order of ties.
#include "weighted_icp/registration/nearest_neighbor_index.h"

#include <algorithm>
#include <atomic>
#include <limits>
#include <sstream>

#include <flann/algorithms/dist.h>
#include <flann/algorithms/kdtree_single_index.h>
#include <flann/util/result_set.h>

#include "weighted_icp/registration/bucket_kd_tree.h"

namespace weighted_icp {

namespace {

using FlannTree = flann::KDTreeSingleIndex<flann::L2_Simple<float>>;

}  // namespace

struct NearestNeighborIndex::Trees {
  explicit Trees(const std::vector<float>& xyz) { tree.build(xyz.data(), xyz.size() / 3); }
  BucketKdTree tree;  // holds its own copy of the points, in leaf order
  // Built on the first tie, under the mutex; read lock-free once published.
  std::mutex flann_mutex;
  std::unique_ptr<FlannTree> flann_storage;
  std::atomic<const FlannTree*> flann{nullptr};
  mutable std::atomic<std::size_t> tie_fallbacks{0};
};

void NearestNeighborIndex::throwUnindexable(std::size_t index, double x, double y, double z) {
  std::ostringstream message;
  message << "point " << index << " (" << x << ", " << y << ", " << z << ") has a coordinate beyond ±" << kMaxCoordinate
          << ", more than the float search index can hold";
  throw std::invalid_argument(message.str());
}

NearestNeighborIndex::NearestNeighborIndex() = default;
NearestNeighborIndex::~NearestNeighborIndex() = default;
NearestNeighborIndex::NearestNeighborIndex(NearestNeighborIndex&&) noexcept = default;

NearestNeighborIndex::NearestNeighborIndex(const NearestNeighborIndex& other)
    : xyz_(other.xyz_), cloud_indices_(other.cloud_indices_) {
  // The trees are deterministic functions of the points: rebuilding gives the same ones.
  if (other.trees_) trees_ = std::make_unique<Trees>(xyz_);
}

NearestNeighborIndex& NearestNeighborIndex::operator=(NearestNeighborIndex other) {
  std::swap(xyz_, other.xyz_);
  std::swap(cloud_indices_, other.cloud_indices_);
  std::swap(trees_, other.trees_);
  // Swapping vectors keeps their buffers, so FLANN's tree (built on xyz_ when a tie needs it) still reads them.
  return *this;
}

bool NearestNeighborIndex::buildFrom(std::vector<float> xyz, std::vector<pcl::index_t> cloud_indices) {
  if (trees_ && xyz == xyz_ && cloud_indices == cloud_indices_) return false;
  trees_.reset();
  xyz_ = std::move(xyz);
  cloud_indices_ = std::move(cloud_indices);
  if (cloud_indices_.empty()) return true;
  if (cloud_indices_.size() > std::numeric_limits<Row>::max())
    throw std::invalid_argument("more than 4,294,967,295 points to index");
  trees_ = std::make_unique<Trees>(xyz_);
  return true;
}

std::size_t NearestNeighborIndex::tieFallbacks() const { return trees_ ? trees_->tie_fallbacks.load() : 0; }

std::size_t NearestNeighborIndex::flannKnn(const float* xyz, Scratch& scratch) const {
  const FlannTree* tree = trees_->flann.load(std::memory_order_acquire);
  if (!tree) {
    std::lock_guard<std::mutex> lock(trees_->flann_mutex);
    if (!trees_->flann_storage) {
      // pcl::KdTreeFLANN's parameters: at most 15 points per leaf. FLANN reorders a copy of the data.
      auto built =
          std::make_unique<FlannTree>(flann::Matrix<float>(const_cast<float*>(xyz_.data()), cloud_indices_.size(), 3),
                                      flann::KDTreeSingleIndexParams(15));
      built->buildIndex();
      trees_->flann_storage = std::move(built);
      trees_->flann.store(trees_->flann_storage.get(), std::memory_order_release);
    }
    tree = trees_->flann_storage.get();
  }
  trees_->tie_fallbacks.fetch_add(1, std::memory_order_relaxed);
  // What FLANN's knnSearch does for one query with PCL's exact, sorted parameters.
  static const flann::SearchParams exact_sorted(-1, 0.0f, true);
  const std::size_t k = scratch.k();
  flann::KNNSimpleResultSet<float> result(k);
  tree->findNeighbors(result, xyz, exact_sorted);
  const std::size_t found = result.size();
  result.copy(scratch.flann_rows_.data(), scratch.sq_distances_.data(), found, true);
  for (std::size_t i = 0; i < found; ++i) scratch.cloud_indices_[i] = cloud_indices_[scratch.flann_rows_[i]];
  return found;
}

std::size_t NearestNeighborIndex::resolve(const float* xyz, const Row* rows, const float* distances, std::size_t count,
                                          Scratch& scratch) const {
  for (std::size_t i = 1; i < count; ++i)
    if (distances[i] == distances[i - 1]) return flannKnn(xyz, scratch);
  const std::size_t found = std::min(count, scratch.k());
  for (std::size_t i = 0; i < found; ++i) {
    scratch.cloud_indices_[i] = cloud_indices_[rows[i]];
    scratch.sq_distances_[i] = distances[i];
  }
  return found;
}

std::size_t NearestNeighborIndex::nearest(const float* xyz, std::size_t count, Row* rows, float* distances) const {
  if (!trees_ || count == 0) return 0;
  return trees_->tree.nearest(xyz, count, rows, distances);
}

std::size_t NearestNeighborIndex::knn(const float* xyz, Scratch& scratch) const {
  if (!trees_) return 0;
  // k + 1: a tie between the k-th and the (k + 1)-th decides which of them FLANN keeps.
  const std::size_t found = nearest(xyz, scratch.k() + 1, scratch.rows_.data(), scratch.distances_.data());
  return resolve(xyz, scratch.rows_.data(), scratch.distances_.data(), found, scratch);
}

bool NearestNeighborIndex::gather(const float* xyz, float radius_sq, std::size_t limit, std::vector<Row>& rows) const {
  if (!trees_) return true;
  return trees_->tree.within(xyz, radius_sq, limit, rows);
}

}  // namespace weighted_icp
