#include "weighted_icp/registration/landmark_point.h"

#include <pcl/impl/pcl_base.hpp>
#include <pcl/kdtree/impl/kdtree_flann.hpp>
#include <pcl/search/impl/kdtree.hpp>
#include <pcl/search/impl/search.hpp>

#include "weighted_icp/registration/weight_strategies.h"

// PCL's base class and kd-trees for LandmarkPoint, so that
// pcl::IterativeClosestPoint and getFitnessScore() link for LandmarkCloud
// without PCL_NO_PRECOMPILE.
template class pcl::PCLBase<weighted_icp::LandmarkPoint>;
template class pcl::KdTreeFLANN<weighted_icp::LandmarkPoint>;
template class pcl::search::Search<weighted_icp::LandmarkPoint>;
template class pcl::search::KdTree<weighted_icp::LandmarkPoint>;

namespace weighted_icp {

LandmarkCloud::Ptr toLandmarkCloud(const LandmarkMap& map, const WeightFunction& weight) {
  const std::vector<double> weights = computeWeights(map, weight);
  auto cloud = std::make_shared<LandmarkCloud>();
  cloud->reserve(map.landmarks.size());
  for (std::size_t i = 0; i < map.landmarks.size(); ++i) {
    const Landmark& landmark = map.landmarks[i];
    LandmarkPoint p;
    p.x = static_cast<float>(landmark.position.x());
    p.y = static_cast<float>(landmark.position.y());
    p.z = static_cast<float>(landmark.position.z());
    p.data[3] = 1.0f;
    p.weight = weights[i];
    p.covariance_norm = static_cast<float>(landmark.covariance.norm());
    p.mean_observation_distance = static_cast<float>(map.meanObservationDistance(landmark));
    p.num_observations = static_cast<std::uint32_t>(landmark.observations.size());
    cloud->push_back(p);
  }
  return cloud;
}

}  // namespace weighted_icp
