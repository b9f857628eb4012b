#pragma once
// Exact k-nearest-neighbour search over the xyz of a point cloud.
//
// It is FLANN's single kd-tree with exactly the parameters of pcl::KdTreeFLANN
// (L2_Simple<float>, 15 points per leaf, non-finite points skipped), so it
// returns the same neighbours, in the same order and with the same float
// distances, ties included. What it adds: it is built once and then searched
// from many threads, each with its own Scratch, with no allocation per query
// on our side.

#include <cmath>
#include <cstddef>
#include <memory>
#include <vector>

#include <flann/algorithms/dist.h>
#include <flann/algorithms/kdtree_single_index.h>
#include <flann/util/result_set.h>
#include <pcl/point_cloud.h>
#include <pcl/types.h>

namespace weighted_icp {

class NearestNeighborIndex {
 public:
  /// Per-thread search state for k-nearest searches with k = `k`.
  class Scratch {
   public:
    explicit Scratch(std::size_t k) : result_(k), indices_(k), cloud_indices_(k), sq_distances_(k) {}
    std::size_t k() const { return indices_.size(); }
    /// Cloud indices and squared distances of the last search, nearest first.
    const std::vector<pcl::index_t>& indices() const { return cloud_indices_; }
    const std::vector<float>& squaredDistances() const { return sq_distances_; }

   private:
    friend class NearestNeighborIndex;
    flann::KNNSimpleResultSet<float> result_;
    std::vector<std::size_t> indices_;
    std::vector<pcl::index_t> cloud_indices_;
    std::vector<float> sq_distances_;
  };

  NearestNeighborIndex() = default;
  NearestNeighborIndex(const NearestNeighborIndex& other);
  NearestNeighborIndex& operator=(NearestNeighborIndex other);
  NearestNeighborIndex(NearestNeighborIndex&&) noexcept = default;

  /// Builds on the finite points of `cloud` (or of `indices` into it). Returns
  /// false, keeping the current tree, when those points are exactly the ones
  /// it was built on: re-setting an unchanged target costs one comparison.
  template <typename PointT>
  bool build(const pcl::PointCloud<PointT>& cloud, const pcl::Indices* indices = nullptr);

  std::size_t size() const { return cloud_indices_.size(); }
  bool empty() const { return cloud_indices_.empty(); }

  /// Searches the scratch.k() nearest points to (x, y, z). Returns how many
  /// were found (fewer when the index is smaller); results are in scratch.
  std::size_t knn(const float* xyz, Scratch& scratch) const;

 private:
  bool buildFrom(std::vector<float> xyz, std::vector<pcl::index_t> cloud_indices);

  using Tree = flann::KDTreeSingleIndex<flann::L2_Simple<float>>;
  std::vector<float> xyz_;                   // the points the tree was built on
  std::vector<pcl::index_t> cloud_indices_;  // tree row -> cloud index
  std::unique_ptr<Tree> tree_;
};

template <typename PointT>
bool NearestNeighborIndex::build(const pcl::PointCloud<PointT>& cloud, const pcl::Indices* indices) {
  const std::size_t n = indices ? indices->size() : cloud.size();
  std::vector<float> xyz;
  std::vector<pcl::index_t> cloud_indices;
  xyz.reserve(3 * n);
  cloud_indices.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto index = indices ? (*indices)[i] : static_cast<pcl::index_t>(i);
    const PointT& p = cloud[index];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    xyz.insert(xyz.end(), {p.x, p.y, p.z});
    cloud_indices.push_back(index);
  }
  return buildFrom(std::move(xyz), std::move(cloud_indices));
}

}  // namespace weighted_icp
