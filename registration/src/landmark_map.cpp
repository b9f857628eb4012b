#include "weighted_icp/registration/landmark_map.h"

#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace weighted_icp {

double LandmarkMap::meanObservationDistance(const Landmark& landmark) const {
  if (landmark.observations.empty()) return 0.0;
  double sum = 0.0;
  for (const auto& observation : landmark.observations) {
    const auto frame = frames.find(observation.frame_id);
    if (frame == frames.end())
      throw std::out_of_range("landmark " + std::to_string(landmark.id) + " is observed by frame " +
                              std::to_string(observation.frame_id) + ", which the map does not have");
    sum += (frame->second.translation() - landmark.position).norm();
  }
  return sum / static_cast<double>(landmark.observations.size());
}

LandmarkMetrics LandmarkMap::metrics(const Landmark& landmark) const {
  return {landmark.covariance, landmark.observations.size(), meanObservationDistance(landmark)};
}

LandmarkMap LandmarkMap::withMinObservations(std::size_t min_observations) const {
  LandmarkMap kept;
  kept.frames = frames;
  for (const auto& landmark : landmarks)
    if (landmark.observations.size() >= min_observations) kept.landmarks.push_back(landmark);
  return kept;
}

LandmarkMap LandmarkMap::miniMap(FrameId first, FrameId last) const {
  LandmarkMap mini;
  for (auto it = frames.lower_bound(first); it != frames.end() && it->first <= last; ++it) mini.frames.insert(*it);
  for (const auto& landmark : landmarks) {
    Landmark kept = landmark;
    kept.observations.clear();
    for (const auto& observation : landmark.observations)
      if (observation.frame_id >= first && observation.frame_id <= last && mini.frames.count(observation.frame_id))
        kept.observations.push_back(observation);
    if (!kept.observations.empty()) mini.landmarks.push_back(std::move(kept));
  }
  return mini;
}

std::vector<LandmarkMap> LandmarkMap::splitIntoMiniMaps(std::size_t frames_per_minimap) const {
  if (frames_per_minimap == 0) throw std::invalid_argument("a mini-map needs at least one frame");
  std::vector<LandmarkMap> minis;
  auto it = frames.begin();
  while (it != frames.end()) {
    const FrameId first = it->first;
    FrameId last = first;
    for (std::size_t n = 0; n < frames_per_minimap && it != frames.end(); ++n, ++it) last = it->first;
    minis.push_back(miniMap(first, last));
  }
  return minis;
}

std::pair<LandmarkMap, LandmarkMap> LandmarkMap::alternateHalves() const {
  std::pair<LandmarkMap, LandmarkMap> halves;
  halves.first.frames = halves.second.frames = frames;
  for (std::size_t i = 0; i < landmarks.size(); ++i)
    (i % 2 == 0 ? halves.first : halves.second).landmarks.push_back(landmarks[i]);
  return halves;
}

void dealOutSharedLandmarks(LandmarkMap& a, LandmarkMap& b) {
  std::set<LandmarkId> in_a, in_b;
  for (const auto& l : a.landmarks) in_a.insert(l.id);
  for (const auto& l : b.landmarks) in_b.insert(l.id);
  const auto keep = [](LandmarkMap& map, const std::set<LandmarkId>& other, LandmarkId parity) {
    std::vector<Landmark> kept;
    for (auto& l : map.landmarks)
      if (!other.count(l.id) || l.id % 2 == parity) kept.push_back(std::move(l));
    map.landmarks = std::move(kept);
  };
  keep(a, in_b, 0);
  keep(b, in_a, 1);
}

Eigen::Isometry3d LandmarkMap::toFirstCameraFrame() {
  if (frames.empty()) throw std::invalid_argument("LandmarkMap::toFirstCameraFrame: the map has no frames");
  const Eigen::Isometry3d first = frames.begin()->second;
  transform(first.inverse());
  return first;
}

void LandmarkMap::transform(const Eigen::Isometry3d& motion) {
  for (auto& [id, pose] : frames) pose = motion * pose;
  const Eigen::Matrix3d rotation = motion.linear();
  for (auto& landmark : landmarks) {
    landmark.position = motion * landmark.position;
    landmark.covariance = rotation * landmark.covariance * rotation.transpose();
  }
}

}  // namespace weighted_icp
