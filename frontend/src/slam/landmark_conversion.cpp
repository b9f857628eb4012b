// Front-end map -> registration's landmark model (see landmark_conversion.h
// for what maps to what).

#include "weighted_icp/frontend/slam/landmark_conversion.h"

namespace weighted_icp::frontend {

LandmarkMap toLandmarkMap(const Map& map) {
  LandmarkMap landmarks;
  for (const Keyframe& keyframe : map.keyframes()) landmarks.frames.emplace(keyframe.id, keyframe.pose_wc);
  for (const MapPoint& point : map.mapPoints()) {
    Landmark landmark;
    landmark.id = point.id;
    landmark.position = point.position;
    landmark.covariance = point.covariance;
    landmark.observations.reserve(point.observations.size());
    for (const MapPointObservation& o : point.observations)
      landmark.observations.push_back({o.keyframe, o.pixel.x(), o.pixel.y()});
    landmarks.landmarks.push_back(std::move(landmark));
  }
  return landmarks;
}

LandmarkCloud::Ptr toWeightedLandmarkCloud(const Map& map, const WeightFunction& weight) {
  return toLandmarkCloud(toLandmarkMap(map), weight);
}

}  // namespace weighted_icp::frontend
