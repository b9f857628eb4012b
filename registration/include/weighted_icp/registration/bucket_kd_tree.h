#pragma once
// An exact 3-D kd-tree for small-k searches, points stored in leaf order.
//
// Why not nanoflann's tree (which it replaced in NearestNeighborIndex): the
// correspondence search asks for k + 1 = 6 or 4(k + 1) = 24 neighbours of
// queries that are themselves spatially coherent, on clouds of 3k to 1M
// points. Here the points are copied in the order of the leaves, so a leaf is
// one contiguous run of coordinates (no per-point indirection through a row table),
// (one array per axis, so that a leaf's distances are computed as one
// vectorised loop), every split is the median of the widest axis (balanced depth whatever the
// density, and it terminates on any number of duplicates), and the search
// keeps per-axis squared gaps to the cell, as Arya and Mount's incremental
// distance does.
//
// Exact in float: a point's squared distance is computed term by term as
// NearestNeighborIndex::squaredDistance (FLANN's and nanoflann's L2_Simple),
// and a cell is skipped only when the float sum of its per-axis squared gaps
// is at least the current k-th distance. Each gap is a float difference to a
// plane that every point of the cell lies beyond, so (rounding being
// monotone) each squared gap is at most the point's squared term on that axis
// and their float sum at most the point's float distance: a skipped point can
// never have been nearer than the k-th. Among equal distances the rows come in
// any order (NearestNeighborIndex::resolve() handles ties).

#include <cstddef>
#include <cstdint>
#include <vector>

namespace weighted_icp {

class BucketKdTree {
 public:
  /// Row of a point: its position in the xyz array the tree was built from.
  using Row = std::uint32_t;
  /// Points per leaf (at most): measured on the real map's halves against 6, 12 and 24 (docs/performance.md).
  static constexpr std::size_t kDefaultLeafSize = 12;
  /// Largest leaf size build() accepts (larger ones are clamped to it).
  static constexpr std::size_t kMaxLeafSize = 64;

  /// @brief Builds on `n` points given as packed xyz (copied: the tree does not keep `xyz`).
  /// @param xyz        3n floats, finite
  /// @param n          number of points (< 2^32)
  /// @param leaf_size  most points per leaf (clamped to 1 .. kMaxLeafSize)
  void build(const float* xyz, std::size_t n, std::size_t leaf_size = kDefaultLeafSize);

  /// @brief Points indexed.
  std::size_t size() const { return rows_.size(); }

  /// @brief The `count` nearest rows to `query` (fewer when the tree is smaller), nearest first; among equal
  /// squared distances in any order.
  /// @param query      xyz
  /// @param count      how many
  /// @param rows       receives the rows (room for `count`)
  /// @param distances  receives their float squared distances (room for `count`)
  /// @return how many were found
  std::size_t nearest(const float* query, std::size_t count, Row* rows, float* distances) const;

  /// @brief Appends every row within float squared distance `radius_sq` of `query` (any order), unless `rows`
  /// would hold more than `limit`: then it stops early and returns false (`rows` then holds a part).
  /// @param query      xyz
  /// @param radius_sq  squared radius (inclusive)
  /// @param limit      most rows wanted
  /// @param rows       appended to
  bool within(const float* query, float radius_sq, std::size_t limit, std::vector<Row>& rows) const;

 private:
  struct Node {
    float low = 0.0f;         // every point of the first child has coordinate <= low on axis
    float high = 0.0f;        // every point of the second child has coordinate >= high
    std::uint32_t begin = 0;  // the node's points: [begin, end) in leaf order
    std::uint32_t end = 0;
    std::uint32_t first = 0;  // index of the first child (the second is first + 1); 0: a leaf
    std::uint32_t axis = 0;
  };
  struct Nearest;
  struct NearestMany;
  struct Within;

  void split(std::uint32_t node, std::vector<Row>& order, const float* xyz, std::size_t leaf_size);
  /// Searches the subtree of `node`; false when the result asked to stop.
  template <typename Result>
  bool descend(std::uint32_t node, const float* query, float* gaps, Result& result) const;

  std::vector<Node> nodes_;
  std::vector<float> xs_, ys_, zs_;  // coordinates in leaf order, one array per axis
  std::vector<Row> rows_;            // leaf order -> row
};

}  // namespace weighted_icp
