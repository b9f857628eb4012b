#pragma once
// A landmark as a PCL point: position, its weight and the raw metrics the
// weight strategies use, so weighted clouds can be saved and loaded as PCD.
// The library instantiates PCL's kd-trees for it, so pcl::IterativeClosestPoint
// and pcl::io work on LandmarkCloud without PCL_NO_PRECOMPILE.

#include <cstdint>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/register_point_struct.h>

#include "weighted_icp/registration/landmark_map.h"
#include "weighted_icp/registration/weight_strategies.h"

namespace weighted_icp {

struct EIGEN_ALIGN16 LandmarkPoint {
  PCL_ADD_POINT4D;        // x, y, z and padding, as every PCL xyz point type
  double weight;          // double: covariance weights differ only in the 5th digit
  float covariance_norm;  // Frobenius norm of the position covariance
  float mean_observation_distance;
  std::uint32_t num_observations;
  PCL_MAKE_ALIGNED_OPERATOR_NEW
};

using LandmarkCloud = pcl::PointCloud<LandmarkPoint>;

/// One point per landmark of `map`, in order, weighted with `weight`.
LandmarkCloud::Ptr toLandmarkCloud(const LandmarkMap& map, const WeightFunction& weight);

}  // namespace weighted_icp

POINT_CLOUD_REGISTER_POINT_STRUCT(
    weighted_icp::LandmarkPoint,
    (float, x, x)(float, y, y)(float, z, z)(double, weight, weight)(float, covariance_norm, covariance_norm)(
        float, mean_observation_distance, mean_observation_distance)(std::uint32_t, num_observations, num_observations))
