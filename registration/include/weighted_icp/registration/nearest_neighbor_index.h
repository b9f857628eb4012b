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
#include <stdexcept>
#include <string>
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

  /// @brief Largest |coordinate| the index accepts (1e18 m).
  /// FLANN splits a node at (min + max) / 2 in float: beyond FLT_MAX / 2 that is
  /// infinite, the split never divides the points and the build recurses
  /// without bound (a stack overflow). Below 1e18 no sum and no squared
  /// distance between two points (at most 12e36) overflows float either.
  static constexpr double kMaxCoordinate = 1e18;

  /// @brief Whether a finite point can be indexed (every |coordinate| <= kMaxCoordinate).
  /// @param x, y, z  the point's coordinates
  static bool fits(float x, float y, float z) {
    return std::abs(x) <= kMaxCoordinate && std::abs(y) <= kMaxCoordinate && std::abs(z) <= kMaxCoordinate;
  }

  /// @brief Throws std::invalid_argument "point <index> (x, y, z) has a coordinate beyond ±1e18 ...".
  /// @param index    the point's index in its cloud
  /// @param x, y, z  its coordinates
  [[noreturn]] static void throwUnindexable(std::size_t index, double x, double y, double z);

  /// @brief Checks every finite point of `cloud` with fits(), before any kd-tree (ours or PCL's, which is
  /// the same FLANN tree) is built on it.
  /// @param cloud  the cloud to be indexed
  /// @param what   names the cloud in the message ("target", "source")
  template <typename PointT>
  static void requireIndexable(const pcl::PointCloud<PointT>& cloud, const std::string& what);

  NearestNeighborIndex() = default;
  NearestNeighborIndex(const NearestNeighborIndex& other);
  NearestNeighborIndex& operator=(NearestNeighborIndex other);
  NearestNeighborIndex(NearestNeighborIndex&&) noexcept = default;

  /// Builds on the finite points of `cloud` (or of `indices` into it); throws
  /// std::invalid_argument naming the first point that does not fit(). Returns
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
    if (!fits(p.x, p.y, p.z)) throwUnindexable(static_cast<std::size_t>(index), p.x, p.y, p.z);
    xyz.insert(xyz.end(), {p.x, p.y, p.z});
    cloud_indices.push_back(index);
  }
  return buildFrom(std::move(xyz), std::move(cloud_indices));
}

template <typename PointT>
void NearestNeighborIndex::requireIndexable(const pcl::PointCloud<PointT>& cloud, const std::string& what) {
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const PointT& p = cloud[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    if (fits(p.x, p.y, p.z)) continue;
    try {
      throwUnindexable(i, p.x, p.y, p.z);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(what + " " + e.what());
    }
  }
}

}  // namespace weighted_icp
