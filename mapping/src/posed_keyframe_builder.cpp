// Posed keyframes (see posed_keyframe_builder.h): features, their depths,
// landmarks and the association with the previous keyframe.

#include "weighted_icp/mapping/posed_keyframe_builder.h"

#include <cmath>
#include <limits>
#include <stdexcept>

#include <opencv2/calib3d.hpp>

#include "weighted_icp/frontend/perception/depth_registration.h"
#include "weighted_icp/mapping/binary_vocabulary.h"

namespace weighted_icp::mapping {

namespace {

/// Undistorted pixel positions of the keypoints.
std::vector<Eigen::Vector2d> undistortedPixels(const std::vector<cv::KeyPoint>& keypoints,
                                               const PinholeCamera& camera) {
  std::vector<cv::Point2f> detected, undistorted;
  for (const cv::KeyPoint& k : keypoints) detected.push_back(k.pt);
  if (camera.hasDistortion() && !detected.empty())
    cv::undistortPoints(detected, undistorted, camera.cameraMatrix(), camera.distortionCoefficients(), cv::noArray(),
                        camera.cameraMatrix());
  else
    undistorted = detected;
  std::vector<Eigen::Vector2d> pixels;
  for (const cv::Point2f& p : undistorted) pixels.emplace_back(p.x, p.y);
  return pixels;
}

/// The previous keyframe's landmarks that project into the image: pixel, id, descriptor.
struct Projected {
  Eigen::Vector2d pixel;
  frontend::MapPointId id;
  BinaryDescriptor descriptor;
};

std::vector<Projected> projectPrevious(const frontend::Map& map, frontend::KeyframeId previous,
                                       const Eigen::Isometry3d& pose_wc, const PinholeCamera& camera) {
  std::vector<Projected> result;
  for (const frontend::Keyframe& keyframe : map.keyframes()) {
    if (keyframe.id != previous) continue;
    for (frontend::MapPointId id : keyframe.observed_points) {
      const auto point = map.mapPoint(id);
      if (!point || point->descriptor.empty()) continue;
      const Eigen::Vector2d pixel = camera.project(pose_wc.inverse() * point->position);
      if (pixel.allFinite() && camera.inImage(pixel))
        result.push_back({pixel, id, toBinaryDescriptors(point->descriptor).front()});
    }
  }
  return result;
}

/// Each of keyframe `id`'s features with a depth as a landmark observation: of the landmark of `previous` within
/// the association radius with the closest descriptor (at most max_hamming_distance off), else of a new landmark at
/// its back-projection with the depth noise model's covariance.
void addLandmarks(frontend::Map& map, frontend::KeyframeId id, const frontend::Keyframe& keyframe,
                  const std::vector<Projected>& previous, const PinholeCamera& camera,
                  const PosedKeyframeOptions& options) {
  const std::vector<BinaryDescriptor> descriptors = toBinaryDescriptors(keyframe.descriptors);
  const double radius2 = options.association_radius_px * options.association_radius_px;
  const Eigen::Isometry3d& pose_wc = keyframe.pose_wc;
  for (std::size_t f = 0; f < descriptors.size(); ++f) {
    const double z = keyframe.depths[f];
    if (z <= 0.0) continue;
    const Eigen::Vector2d& pixel = keyframe.pixels[f];
    const frontend::MapPointObservation observation{id, pixel, z};
    const Projected* associated = nullptr;
    int best = options.max_hamming_distance + 1;
    for (const Projected& p : previous) {
      if ((p.pixel - pixel).squaredNorm() > radius2) continue;
      const int d = hammingDistance(p.descriptor, descriptors[f]);
      if (d < best) best = d, associated = &p;
    }
    const cv::Mat descriptor = keyframe.descriptors.row(static_cast<int>(f)).clone();
    if (associated) {
      // The first estimate's position stays: the pose is given, so later ones add nothing but noise.
      const auto point = map.mapPoint(associated->id);
      map.addObservation(associated->id, observation, point->position, point->covariance, descriptor);
    } else {
      frontend::MapPoint point;
      point.position = pose_wc * camera.backProject(pixel.x(), pixel.y(), z);
      point.covariance = pose_wc.linear() *
                         frontend::pointCovarianceCamera(camera, pixel.x(), pixel.y(), z, options.noise) *
                         pose_wc.linear().transpose();
      point.descriptor = descriptor;
      point.observations.push_back(observation);
      map.addMapPoint(std::move(point));
    }
  }
}

}  // namespace

PosedKeyframeBuilder::PosedKeyframeBuilder(const PinholeCamera& camera, PosedKeyframeOptions options)
    : camera_(camera), options_(options), extractor_(options.features) {}

frontend::KeyframeId PosedKeyframeBuilder::add(const RgbdFrame& input, std::size_t frame_id,
                                               const Eigen::Isometry3d& pose_wc) {
  const cv::Size depth_size = camera_.depthImageSize();
  if (input.color.empty() || input.depth.empty() || input.depth.type() != CV_32FC1 ||
      input.color.size() != cv::Size(camera_.width, camera_.height) || input.depth.size() != depth_size)
    throw std::invalid_argument("PosedKeyframeBuilder: frame " + std::to_string(frame_id) + " needs colour of " +
                                std::to_string(camera_.width) + "x" + std::to_string(camera_.height) +
                                " and CV_32F depth of " + std::to_string(depth_size.width) + "x" +
                                std::to_string(depth_size.height));
  // An unregistered sensor's depth moved into the colour pixels first, as the front end does.
  RgbdFrame frame = input;
  if (camera_.unregistered_depth) frame.depth = frontend::registerDepthToColor(input.depth, camera_);
  const frontend::ExtractedFeatures features = extractor_.extract(frame.gray());
  frontend::Keyframe keyframe;
  keyframe.frame_id = frame_id;
  keyframe.timestamp = frame.timestamp;
  keyframe.pose_wc = pose_wc;
  keyframe.keypoints = features.keypoints;
  keyframe.descriptors = features.descriptors;
  keyframe.pixels = undistortedPixels(features.keypoints, camera_);
  for (const cv::KeyPoint& k : features.keypoints) {
    const float z = frame.depth.at<float>(cvRound(k.pt.y), cvRound(k.pt.x));
    keyframe.depths.push_back(std::isfinite(z) && z >= options_.min_depth && z <= options_.max_depth ? z : 0.0);
  }
  const std::vector<Projected> previous =
      has_previous_ ? projectPrevious(map_, previous_, pose_wc, camera_) : std::vector<Projected>{};
  const frontend::KeyframeId id = map_.addKeyframe(keyframe);
  addLandmarks(map_, id, keyframe, previous, camera_, options_);
  has_previous_ = true;
  previous_ = id;
  return id;
}

}  // namespace weighted_icp::mapping
