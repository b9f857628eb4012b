// Explicit instantiation for the common point types keeps users' compile times
// down, as PCL does with its own templates.
#include "weighted_icp/registration/impl/weighted_correspondence_estimation.hpp"

#include <pcl/point_types.h>

#include "weighted_icp/registration/landmark_point.h"

#define WEIGHTED_ICP_INSTANTIATE_FOR_SCALARS(P)                          \
  WEIGHTED_ICP_INSTANTIATE_WeightedCorrespondenceEstimation(P, P, float) \
      WEIGHTED_ICP_INSTANTIATE_WeightedCorrespondenceEstimation(P, P, double)

WEIGHTED_ICP_INSTANTIATE_FOR_SCALARS(pcl::PointXYZ)
WEIGHTED_ICP_INSTANTIATE_FOR_SCALARS(pcl::PointXYZI)
WEIGHTED_ICP_INSTANTIATE_FOR_SCALARS(pcl::PointNormal)
WEIGHTED_ICP_INSTANTIATE_FOR_SCALARS(weighted_icp::LandmarkPoint)
