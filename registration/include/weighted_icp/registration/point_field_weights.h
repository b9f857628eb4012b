#pragma once
// Reading per-point weights from a named field of any registered PCL point type.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <pcl/PCLPointField.h>
#include <pcl/common/io.h>
#include <pcl/point_cloud.h>

namespace weighted_icp {

/// The value of a scalar field of one point, whatever its numeric type.
double readScalarField(const std::uint8_t* point_bytes, const pcl::PCLPointField& field);

/// Throws std::invalid_argument naming `what` and the index of the first
/// negative or non-finite weight.
void checkWeights(const std::vector<double>& weights, const std::string& what);

/// The field's value for every point, or nothing when PointT has no such field.
template <typename PointT>
std::optional<std::vector<double>> readWeightField(const pcl::PointCloud<PointT>& cloud,
                                                   const std::string& field_name) {
  for (const auto& field : pcl::getFields<PointT>()) {
    if (field.name != field_name) continue;
    std::vector<double> weights(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i)
      weights[i] = readScalarField(reinterpret_cast<const std::uint8_t*>(&cloud[i]), field);
    return weights;
  }
  return std::nullopt;
}

}  // namespace weighted_icp
