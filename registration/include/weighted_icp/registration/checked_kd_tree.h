#pragma once
// A pcl::search::KdTree that refuses, with an exception naming the point, a cloud its float FLANN tree cannot
// hold, instead of recursing without bound (a stack overflow) while building on it.
//
// Why it exists: pcl::Registration::align() builds its own kd-tree on the target (Registration::initCompute)
// before any correspondence estimation runs, so WeightedCorrespondenceEstimation's own check comes too late to
// save a user's pcl::IterativeClosestPoint from a target with coordinates beyond ±1e18. Giving ICP this tree
// moves the check to the moment PCL builds its tree:
//
//   icp.setSearchMethodTarget(std::make_shared<weighted_icp::CheckedKdTree<PointT>>());
//
// align() then throws std::invalid_argument "target point 12 (...) has a coordinate beyond ±1e+18 ...".
// The source needs no such tree: PCL builds none on it for ICP, and the reciprocal rule's source index is
// WeightedCorrespondenceEstimation's own, checked. A pipeline with PCL's own estimation or reciprocal tree
// can pass one as well (setSearchMethodSource, with what = "source"). LandmarkAligner checks its clouds itself.

#include <memory>
#include <string>

#include <pcl/search/kdtree.h>

#include "weighted_icp/registration/nearest_neighbor_index.h"

namespace weighted_icp {

/// @brief pcl::search::KdTree (the same FLANN tree, the same neighbours) whose setInputCloud() first checks
/// every finite point it will index with NearestNeighborIndex::fits().
/// @tparam PointT a PCL point type with x, y, z
template <typename PointT>
class CheckedKdTree : public pcl::search::KdTree<PointT> {
 public:
  using Ptr = std::shared_ptr<CheckedKdTree<PointT>>;
  using ConstPtr = std::shared_ptr<const CheckedKdTree<PointT>>;
  using Base = pcl::search::KdTree<PointT>;

  /// @brief An empty tree.
  /// @param what names the cloud in errors ("target" for setSearchMethodTarget, "source" for the reciprocal tree)
  /// @param sorted as pcl::search::KdTree: return neighbours sorted by distance
  explicit CheckedKdTree(std::string what = "target", bool sorted = true) : Base(sorted), what_(std::move(what)) {
    this->name_ = "CheckedKdTree";
  }

  /// @brief Checks the points to be indexed (all, or `indices`), then builds PCL's tree on them.
  /// Throws std::invalid_argument naming the first finite point beyond NearestNeighborIndex::kMaxCoordinate,
  /// with the tree left as it was.
  /// @param cloud the cloud to index
  /// @param indices the points of `cloud` to index; null for all
  void setInputCloud(const typename Base::PointCloudConstPtr& cloud,
                     const typename Base::IndicesConstPtr& indices = typename Base::IndicesConstPtr()) override {
    if (cloud) {
      if (indices) {
        for (const auto index : *indices) checkPoint(*cloud, static_cast<std::size_t>(index));
      } else {
        NearestNeighborIndex::requireIndexable(*cloud, what_);
      }
    }
    Base::setInputCloud(cloud, indices);
  }

 private:
  void checkPoint(const pcl::PointCloud<PointT>& cloud, std::size_t index) const {
    if (index >= cloud.size()) return;  // PCL's own tree reports bad indices
    const PointT& p = cloud[index];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z) || NearestNeighborIndex::fits(p.x, p.y, p.z))
      return;
    try {
      NearestNeighborIndex::throwUnindexable(index, p.x, p.y, p.z);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(what_ + " " + e.what());
    }
  }

  std::string what_;
};

}  // namespace weighted_icp
