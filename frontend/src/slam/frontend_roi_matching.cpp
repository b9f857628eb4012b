// Frontend's issue #11 options: matching in regions of interest (projection or
// the KD-tree paper's keyframe-to-frame homography, Eq. 8) and the front-end
// paper's Eq. 6 distance history for moving points.

#include <cmath>
#include <limits>

#include "weighted_icp/frontend/slam/frontend.h"

namespace weighted_icp::frontend {

std::vector<cv::DMatch> Frontend::localDescriptorMatches(const Frame& frame, const Eigen::Isometry3d& guess_wc,
                                                         double gate_px) const {
  if (options_.match_region == MatchRegion::Everywhere) return matcher_.match(frame.descriptors);
  // The region of interest is the projection gate itself, applied before the
  // descriptor search instead of after it.
  RoiMatchOptions roi;
  roi.radius_px = gate_px;
  roi.ratio = options_.matcher.ratio;
  roi.max_hamming_distance = options_.matcher.max_hamming_distance;
  roi.cross_check_unique = options_.matcher.cross_check_unique;
  return matchInRegionsOfInterest(frame.descriptors, frame.pixels, local_map_.descriptors,
                                  predictLocalMapPixels(guess_wc), roi);
}

std::vector<Eigen::Vector2d> Frontend::predictLocalMapPixels(const Eigen::Isometry3d& guess_wc) const {
  const Eigen::Isometry3d guess_cw = guess_wc.inverse();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<Eigen::Matrix3d> homographies;
  if (options_.match_region == MatchRegion::Homography)
    for (const Plane& plane : keyframe_planes_.planes_world)
      homographies.push_back(keyframeToFrameHomography(camera_, keyframe_planes_.pose_wc, guess_wc, plane));
  std::vector<Eigen::Vector2d> predicted(local_map_.ids.size(), Eigen::Vector2d(nan, nan));
  for (std::size_t i = 0; i < local_map_.ids.size(); ++i) {
    if (!homographies.empty()) {
      const auto seen = keyframe_planes_.points.find(local_map_.ids[i]);
      if (seen != keyframe_planes_.points.end() && seen->second.second >= 0) {
        predicted[i] = applyHomography(homographies[static_cast<std::size_t>(seen->second.second)], seen->second.first);
        continue;
      }
    }
    // Off every plane (or not seen by the last keyframe): the point's own depth predicts it.
    const Eigen::Vector3d point_camera = guess_cw * local_map_.positions[i];
    if (point_camera.z() > 0.0) predicted[i] = camera_.project(point_camera);
  }
  return predicted;
}

void Frontend::recordKeyframePlanes(const Frame& frame) {
  keyframe_planes_ = KeyframePlanes{};
  if (options_.match_region != MatchRegion::Homography) return;
  keyframe_planes_.pose_wc = frame.pose_wc;
  std::vector<Eigen::Vector3d> points_camera(frame.size(), Eigen::Vector3d::Constant(std::nan("")));
  for (std::size_t i = 0; i < frame.size(); ++i)
    if (frame.hasDepth(i))
      points_camera[i] = camera_.backProject(frame.pixels[i].x(), frame.pixels[i].y(), frame.depths[i]);
  const PlaneSet found = fitPlanes(points_camera, options_.keyframe_planes);
  for (const Plane& plane : found.planes) keyframe_planes_.planes_world.push_back(planeToWorld(plane, frame.pose_wc));
  keyframe_planes_.plane_of_feature = found.plane_of_point;
}

void Frontend::recordKeyframePixel(MapPointId id, const Frame& frame, std::size_t feature) {
  if (options_.match_region != MatchRegion::Homography) return;
  const int plane =
      feature < keyframe_planes_.plane_of_feature.size() ? keyframe_planes_.plane_of_feature[feature] : -1;
  keyframe_planes_.points[id] = {frame.pixels[feature], plane};
}

std::vector<bool> Frontend::flagByEpipolarHistory(const Frame& frame, const LocalMatches& matched,
                                                  const Eigen::Isometry3d& pose_wc) {
  std::vector<std::uint64_t> ids;
  ids.reserve(matched.size());
  for (const auto& pair : matched.ids) ids.push_back(static_cast<std::uint64_t>(pair.second));
  return dynamic_history_.update(frame.id, ids, matched.pixels, pose_wc, camera_);
}

}  // namespace weighted_icp::frontend
