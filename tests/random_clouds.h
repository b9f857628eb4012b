#pragma once
// Seeded random point clouds for the registration tests, with exact duplicates
// where a test needs distance ties (the order of equal neighbours is PCL's).

#include <cstddef>
#include <memory>
#include <random>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

namespace weighted_icp::testing {

/// @brief `n` points uniform in [-half_extent, half_extent]^3, then `n / duplicate_divisor` exact copies of
/// points i * 7 % n (none when duplicate_divisor is 0).
/// @param n random points
/// @param seed the generator's seed (std::mt19937)
/// @param half_extent half the side of the cube
/// @param duplicate_divisor one duplicate per this many points, 0 for none
inline pcl::PointCloud<pcl::PointXYZ>::Ptr randomCloud(std::size_t n, unsigned seed, float half_extent,
                                                       std::size_t duplicate_divisor) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> coordinate(-half_extent, half_extent);
  auto cloud = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  for (std::size_t i = 0; i < n; ++i)
    cloud->push_back(pcl::PointXYZ(coordinate(rng), coordinate(rng), coordinate(rng)));
  if (duplicate_divisor > 0)
    for (std::size_t i = 0; i < n / duplicate_divisor; ++i) cloud->push_back((*cloud)[i * 7 % n]);
  return cloud;
}

}  // namespace weighted_icp::testing
