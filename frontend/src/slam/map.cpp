#include "weighted_icp/frontend/slam/map.h"

#include <algorithm>
#include <iterator>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>

#include "weighted_icp/core/nearest_rotation.h"

namespace weighted_icp::frontend {

KeyframeId Map::addKeyframe(Keyframe keyframe) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++revision_;
  keyframe.id = next_keyframe_id_++;
  keyframe.observed_points.clear();
  const KeyframeId id = keyframe.id;
  // A new keyframe is tracked from the newest one, in the frame the corrections so far have put it in.
  corrected_by_[id] = corrected_by_.empty() ? Eigen::Isometry3d::Identity() : corrected_by_.rbegin()->second;
  keyframes_.emplace(id, std::move(keyframe));
  return id;
}

MapPointId Map::addMapPoint(MapPoint point) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++revision_;
  point.id = next_point_id_++;
  for (const auto& observation : point.observations) {
    const auto keyframe = keyframes_.find(observation.keyframe);
    if (keyframe == keyframes_.end())
      throw std::invalid_argument("map point observed by unknown keyframe " + std::to_string(observation.keyframe));
    keyframe->second.observed_points.push_back(point.id);
  }
  const MapPointId id = point.id;
  points_.emplace(id, std::move(point));
  return id;
}

void Map::addObservation(MapPointId id, const MapPointObservation& observation, const Eigen::Vector3d& position,
                         const Eigen::Matrix3d& covariance, const cv::Mat& descriptor) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto point = points_.find(id);
  const auto keyframe = keyframes_.find(observation.keyframe);
  if (point == points_.end() || keyframe == keyframes_.end()) return;  // removed by the backend meanwhile
  ++revision_;
  point->second.observations.push_back(observation);
  point->second.position = position;
  point->second.covariance = covariance;
  point->second.descriptor = descriptor;
  keyframe->second.observed_points.push_back(id);
}

std::uint64_t Map::revision() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return revision_;
}

std::optional<Eigen::Isometry3d> Map::keyframePose(KeyframeId id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto keyframe = keyframes_.find(id);
  if (keyframe == keyframes_.end()) return std::nullopt;
  return keyframe->second.pose_wc;
}

std::optional<MapPoint> Map::mapPoint(MapPointId id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto point = points_.find(id);
  if (point == points_.end()) return std::nullopt;
  return point->second;
}

std::vector<MapPointId> Map::currentSegmentPoints(std::size_t keyframes) const {
  std::set<MapPointId> ids;
  if (keyframes_.empty()) return {};
  const std::size_t segment = keyframes_.rbegin()->second.segment;
  std::size_t taken = 0;
  for (auto it = keyframes_.rbegin(); it != keyframes_.rend() && taken < keyframes; ++it, ++taken) {
    if (it->second.segment != segment) break;
    for (const MapPointId id : it->second.observed_points)
      if (points_.count(id)) ids.insert(id);
  }
  return {ids.begin(), ids.end()};
}

LocalMap Map::localMap(std::size_t keyframes) const {
  std::lock_guard<std::mutex> lock(mutex_);
  LocalMap local;
  local.revision = revision_;
  local.ids = currentSegmentPoints(keyframes);
  local.positions.reserve(local.ids.size());
  for (const MapPointId id : local.ids) {
    const MapPoint& point = points_.at(id);
    local.positions.push_back(point.position);
    local.descriptors.push_back(point.descriptor);
  }
  return local;
}

MapWindow Map::window(std::size_t keyframes) const {
  std::lock_guard<std::mutex> lock(mutex_);
  MapWindow window;
  window.corrections = corrections_;
  if (keyframes_.empty()) return window;
  const std::size_t segment = keyframes_.rbegin()->second.segment;
  for (auto it = keyframes_.rbegin(); it != keyframes_.rend() && window.keyframes.size() < keyframes; ++it) {
    if (it->second.segment != segment) break;
    window.keyframes.push_back(it->second);
  }
  std::reverse(window.keyframes.begin(), window.keyframes.end());
  for (const MapPointId id : currentSegmentPoints(keyframes)) window.points.push_back(points_.at(id));
  return window;
}

void Map::applyOptimization(const MapWindow& optimised,
                            const std::vector<std::pair<MapPointId, KeyframeId>>& rejected_observations) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (optimised.corrections != corrections_) return;  // optimised in the frame before a loop correction
  ++revision_;
  for (const auto& keyframe : optimised.keyframes) {
    const auto it = keyframes_.find(keyframe.id);
    if (it != keyframes_.end()) it->second.pose_wc = keyframe.pose_wc;
  }
  for (const auto& point : optimised.points) {
    const auto it = points_.find(point.id);
    if (it == points_.end()) continue;
    it->second.position = point.position;
    it->second.covariance = point.covariance;
  }
  for (const auto& [point_id, rejected_keyframe] : rejected_observations) {
    const KeyframeId keyframe_id = rejected_keyframe;  // a lambda cannot capture a structured binding in C++17
    const auto point = points_.find(point_id);
    if (point == points_.end()) continue;
    auto& observations = point->second.observations;
    observations.erase(std::remove_if(observations.begin(), observations.end(),
                                      [&](const MapPointObservation& o) { return o.keyframe == keyframe_id; }),
                       observations.end());
    const auto keyframe = keyframes_.find(keyframe_id);
    if (keyframe != keyframes_.end()) {
      auto& ids = keyframe->second.observed_points;
      ids.erase(std::remove(ids.begin(), ids.end(), point_id), ids.end());
    }
    if (observations.empty()) points_.erase(point);
  }
}

KeyframePoses Map::keyframePoses() const {
  std::lock_guard<std::mutex> lock(mutex_);
  KeyframePoses poses;
  poses.corrections = corrections_;
  for (const auto& [id, keyframe] : keyframes_) {
    poses.ids.push_back(id);
    poses.poses_wc.push_back(keyframe.pose_wc);
    poses.segments.push_back(keyframe.segment);
    poses.odometry_wc.push_back(corrected_by_.at(id).inverse() * keyframe.pose_wc);
  }
  return poses;
}

std::uint64_t Map::corrections() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return corrections_;
}

bool Map::postCorrection(PoseGraphCorrection correction) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (correction.base_corrections != corrections_) return false;
  pending_correction_ = std::move(correction);
  return true;
}

bool Map::correctionPending() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return pending_correction_.has_value();
}

Eigen::Isometry3d Map::deltaOf(const PoseGraphCorrection& correction, KeyframeId id) {
  auto after = correction.delta_wc.upper_bound(id);
  if (after == correction.delta_wc.begin()) return Eigen::Isometry3d::Identity();
  return std::prev(after)->second;
}

std::optional<Eigen::Isometry3d> Map::applyPendingCorrection(KeyframeId follow) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!pending_correction_) return std::nullopt;
  const PoseGraphCorrection correction = std::move(*pending_correction_);
  pending_correction_.reset();
  ++revision_;
  ++corrections_;
  for (auto& [id, keyframe] : keyframes_) {
    const Eigen::Isometry3d delta = deltaOf(correction, id);
    // Composed again at every correction: kept rigid, or rounding accumulates (1e-8 seen after 19 loops).
    keyframe.pose_wc = withNearestRotation(delta * keyframe.pose_wc);
    corrected_by_[id] = withNearestRotation(delta * corrected_by_[id]);
  }
  for (auto& [id, point] : points_) {
    if (point.observations.empty()) continue;
    KeyframeId reference = point.observations.front().keyframe;
    for (const auto& observation : point.observations) reference = std::min(reference, observation.keyframe);
    const Eigen::Isometry3d delta = deltaOf(correction, reference);
    point.position = delta * point.position;
    point.covariance = delta.linear() * point.covariance * delta.linear().transpose();
  }
  return keyframes_.count(follow) ? deltaOf(correction, follow) : Eigen::Isometry3d::Identity();
}

std::vector<Keyframe> Map::keyframes() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<Keyframe> out;
  out.reserve(keyframes_.size());
  for (const auto& [id, keyframe] : keyframes_) out.push_back(keyframe);
  return out;
}

std::vector<MapPoint> Map::mapPoints() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<MapPoint> out;
  out.reserve(points_.size());
  for (const auto& [id, point] : points_) out.push_back(point);
  return out;
}

template <typename Id, typename Value>
bool Map::copyBlocks(const std::map<Id, Value>& source, std::size_t per_block, std::uint64_t corrections,
                     std::vector<Value>& out) const {
  // Resumed from the last id copied, not from an iterator: the map may change between blocks.
  std::optional<Id> last;
  while (true) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (corrections_ != corrections) return false;
    auto it = last ? source.upper_bound(*last) : source.begin();
    for (std::size_t n = 0; n < per_block && it != source.end(); ++n, ++it) out.push_back(it->second);
    if (it == source.end()) return true;
    last = std::prev(it)->first;
  }
}

MapCopy Map::copyInBlocks(std::size_t keyframes_per_block, std::size_t points_per_block) const {
  keyframes_per_block = std::max<std::size_t>(keyframes_per_block, 1);
  points_per_block = std::max<std::size_t>(points_per_block, 1);
  while (true) {
    MapCopy copy;
    std::uint64_t corrections = 0;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      corrections = corrections_;
      copy.keyframes.reserve(keyframes_.size());
      copy.points.reserve(points_.size());
    }
    if (copyBlocks(keyframes_, keyframes_per_block, corrections, copy.keyframes) &&
        copyBlocks(points_, points_per_block, corrections, copy.points))
      return copy;
  }
}

std::size_t Map::keyframeCount() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return keyframes_.size();
}

std::size_t Map::mapPointCount() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return points_.size();
}

}  // namespace weighted_icp::frontend
