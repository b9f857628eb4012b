#pragma once
// Exact k-nearest-neighbour search over the xyz of a point cloud, with PCL's answers.
//
// pcl::KdTreeFLANN (FLANN's single kd-tree, 15 points per leaf, float L2)
// defines the answer: the k nearest in order, float squared distances, and
// among equal distances the order in which FLANN's traversal met them. The
// search itself runs on our BucketKdTree (faster per query than FLANN's and
// than nanoflann's, which it replaced; docs/performance.md), asking for k + 1 neighbours: when the k + 1 nearest
// distances are all different, the k nearest and their order are determined
// by the distances alone, so any exact index gives FLANN's answer; when two of
// them are equal, the order is FLANN's traversal order, and the query is
// answered by a FLANN tree built on the same points, as PCL's is. The FLANN
// tree is built only when the first such tie appears.
//
// Built once, searched from many threads, each with its own Scratch: no
// allocation per query on our side.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include <pcl/point_cloud.h>
#include <pcl/types.h>

namespace weighted_icp {

class NearestNeighborIndex {
 public:
  /// Row of a point in the index (its position among the indexed points).
  using Row = std::uint32_t;

  /// Per-thread search state for k-nearest searches with k = `k`.
  class Scratch {
   public:
    /// @brief State for searches of the `k` nearest.
    /// @param k  neighbours per search (>= 1)
    explicit Scratch(std::size_t k)
        : rows_(k + 1), distances_(k + 1), flann_rows_(k), cloud_indices_(k), sq_distances_(k) {}
    std::size_t k() const { return cloud_indices_.size(); }
    /// Cloud indices and squared distances of the last search, nearest first.
    const std::vector<pcl::index_t>& indices() const { return cloud_indices_; }
    const std::vector<float>& squaredDistances() const { return sq_distances_; }

   private:
    friend class NearestNeighborIndex;
    std::vector<Row> rows_;         // k + 1 nearest rows, for the tie check
    std::vector<float> distances_;  // their squared distances
    std::vector<std::size_t> flann_rows_;
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

  /// @brief The squared distance as FLANN's L2_Simple<float> (and BucketKdTree) compute it, term by term in float.
  /// @param a, b  two xyz triples
  static float squaredDistance(const float* a, const float* b) {
    const float d0 = a[0] - b[0];
    const float d1 = a[1] - b[1];
    const float d2 = a[2] - b[2];
    float result = d0 * d0;
    result += d1 * d1;
    result += d2 * d2;
    return result;
  }

  NearestNeighborIndex();
  ~NearestNeighborIndex();
  NearestNeighborIndex(const NearestNeighborIndex& other);
  NearestNeighborIndex& operator=(NearestNeighborIndex other);
  NearestNeighborIndex(NearestNeighborIndex&&) noexcept;

  /// @brief Builds on the finite points of `cloud` (or of `indices` into it).
  /// Throws std::invalid_argument naming the first point that does not fit().
  /// @return false, keeping the current tree, when those points are exactly the
  ///         ones it was built on: re-setting an unchanged target costs one comparison
  template <typename PointT>
  bool build(const pcl::PointCloud<PointT>& cloud, const pcl::Indices* indices = nullptr);

  std::size_t size() const { return cloud_indices_.size(); }
  bool empty() const { return cloud_indices_.empty(); }
  /// @brief xyz of an indexed point.
  /// @param row  0 .. size() - 1
  const float* point(Row row) const { return xyz_.data() + 3 * static_cast<std::size_t>(row); }
  /// @brief Cloud index of an indexed point.
  /// @param row  0 .. size() - 1
  pcl::index_t cloudIndex(Row row) const { return cloud_indices_[row]; }

  /// @brief The `count` nearest rows to `xyz` (fewer when the index is smaller), nearest first; among equal
  /// distances in any order. Use resolve() to turn them into PCL's answer.
  /// @param xyz        the query
  /// @param count      how many
  /// @param rows       receives the rows (room for `count`)
  /// @param distances  receives their squared distances (room for `count`)
  /// @return how many were found
  std::size_t nearest(const float* xyz, std::size_t count, Row* rows, float* distances) const;

  /// @brief Searches the scratch.k() nearest points to `xyz`, exactly as pcl::KdTreeFLANN::nearestKSearch.
  /// @param xyz      the query
  /// @param scratch  receives the results
  /// @return how many were found (fewer than k when the index is smaller)
  std::size_t knn(const float* xyz, Scratch& scratch) const;

  /// @brief The same, with the k + 1 nearest rows and distances known already (sorted, from any exact
  /// search): copies them out, or asks FLANN when two of them tie.
  /// @param xyz       the query
  /// @param rows      the min(k + 1, size()) nearest rows, nearest first
  /// @param distances their squared distances (squaredDistance())
  /// @param count     how many entries rows and distances hold
  /// @param scratch   receives the results
  /// @return how many were found
  std::size_t resolve(const float* xyz, const Row* rows, const float* distances, std::size_t count,
                      Scratch& scratch) const;

  /// @brief Appends every row within squared distance `radius_sq` of `xyz` to `rows` (any order), unless
  /// there are more than `limit`: then it stops early and returns false (`rows` then holds a part).
  /// @param xyz        the centre
  /// @param radius_sq  squared radius
  /// @param limit      most rows wanted
  /// @param rows       appended to
  bool gather(const float* xyz, float radius_sq, std::size_t limit, std::vector<Row>& rows) const;

  /// Number of queries answered by FLANN because of a tie, since the last build (for benchmarks).
  std::size_t tieFallbacks() const;

 private:
  struct Trees;
  bool buildFrom(std::vector<float> xyz, std::vector<pcl::index_t> cloud_indices);
  std::size_t flannKnn(const float* xyz, Scratch& scratch) const;

  std::vector<float> xyz_;                   // the points the trees are built on
  std::vector<pcl::index_t> cloud_indices_;  // row -> cloud index
  std::unique_ptr<Trees> trees_;
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
