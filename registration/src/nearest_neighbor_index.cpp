#include "weighted_icp/registration/nearest_neighbor_index.h"

#include <sstream>

namespace weighted_icp {

void NearestNeighborIndex::throwUnindexable(std::size_t index, double x, double y, double z) {
  std::ostringstream message;
  message << "point " << index << " (" << x << ", " << y << ", " << z << ") has a coordinate beyond ±" << kMaxCoordinate
          << ", more than the float search index can hold";
  throw std::invalid_argument(message.str());
}

NearestNeighborIndex::NearestNeighborIndex(const NearestNeighborIndex& other)
    : xyz_(other.xyz_),
      cloud_indices_(other.cloud_indices_),
      tree_(other.tree_ ? std::make_unique<Tree>(*other.tree_) : nullptr) {}

NearestNeighborIndex& NearestNeighborIndex::operator=(NearestNeighborIndex other) {
  std::swap(xyz_, other.xyz_);
  std::swap(cloud_indices_, other.cloud_indices_);
  std::swap(tree_, other.tree_);
  return *this;
}

bool NearestNeighborIndex::buildFrom(std::vector<float> xyz, std::vector<pcl::index_t> cloud_indices) {
  if (tree_ && xyz == xyz_ && cloud_indices == cloud_indices_) return false;
  xyz_ = std::move(xyz);
  cloud_indices_ = std::move(cloud_indices);
  tree_.reset();
  if (cloud_indices_.empty()) return true;
  // pcl::KdTreeFLANN's parameters: at most 15 points per leaf.
  tree_ = std::make_unique<Tree>(flann::Matrix<float>(xyz_.data(), cloud_indices_.size(), 3),
                                 flann::KDTreeSingleIndexParams(15));
  tree_->buildIndex();
  return true;
}

std::size_t NearestNeighborIndex::knn(const float* xyz, Scratch& scratch) const {
  if (!tree_) return 0;
  // What FLANN's knnSearch does for one query with k <= 250 and PCL's exact,
  // sorted parameters, without its per-call allocations and OpenMP region.
  static const flann::SearchParams exact_sorted(-1, 0.0f, true);
  scratch.result_.clear();
  tree_->findNeighbors(scratch.result_, xyz, exact_sorted);
  const std::size_t found = scratch.result_.size();
  scratch.result_.copy(scratch.indices_.data(), scratch.sq_distances_.data(), found, true);
  for (std::size_t i = 0; i < found; ++i) scratch.cloud_indices_[i] = cloud_indices_[scratch.indices_[i]];
  return found;
}

}  // namespace weighted_icp
