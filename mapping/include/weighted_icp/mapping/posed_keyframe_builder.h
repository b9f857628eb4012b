#pragma once
// Keyframes and landmarks from RGB-D frames whose poses are given (ground
// truth or another odometry), without tracking: what vocabularies are trained
// on and what place recognition is evaluated and tested on.

#include <cstddef>
#include <string>

#include <Eigen/Geometry>

#include "weighted_icp/core/camera.h"
#include "weighted_icp/core/rgbd_frame.h"
#include "weighted_icp/frontend/geometry/depth_noise_model.h"
#include "weighted_icp/frontend/perception/feature_extractor.h"
#include "weighted_icp/frontend/slam/map.h"

namespace weighted_icp::mapping {

/// @brief How features become landmarks.
struct PosedKeyframeOptions {
  /// The front end's detector and descriptor (GFTT corners, ORB descriptors).
  frontend::FeatureExtractorOptions features;
  /// Gives each new landmark its covariance (first-order propagation of pixel and depth noise).
  frontend::DepthNoiseModel noise;
  /// Depths outside this range (metres) make no landmark.
  double min_depth = 0.3, max_depth = 5.0;
  /// A feature observes a landmark of the previous keyframe when that landmark projects within this many
  /// pixels of it and their descriptors differ by at most max_hamming_distance bits.
  double association_radius_px = 3.0;
  int max_hamming_distance = 64;
};

/// @brief Adds posed RGB-D frames to a frontend::Map as keyframes, one landmark per feature with depth,
/// associated with the previous keyframe's landmarks by projection and descriptor.
class PosedKeyframeBuilder {
 public:
  /// @brief A builder for one camera.
  /// @param camera intrinsics and distortion of the colour images (keypoints are undistorted)
  /// @param options feature and association settings (the extractor checks its own)
  explicit PosedKeyframeBuilder(const PinholeCamera& camera, PosedKeyframeOptions options = {});

  /// @brief The class name, as PCL classes report it.
  static std::string getClassName() { return "PosedKeyframeBuilder"; }

  /// @brief Extracts the frame's features and adds it as the next keyframe.
  /// @param frame colour of the camera's size and metric CV_32F depth of its depth camera's
  /// (PinholeCamera::depthImageSize; registered to the colour camera first when it is unregistered); anything
  /// else throws std::invalid_argument
  /// @param frame_id its index in the sequence
  /// @param pose_wc its camera-to-world pose
  /// @return the keyframe's id
  frontend::KeyframeId add(const RgbdFrame& frame, std::size_t frame_id, const Eigen::Isometry3d& pose_wc);

  /// @brief The map built so far.
  const frontend::Map& map() const { return map_; }

 private:
  PinholeCamera camera_;
  PosedKeyframeOptions options_;
  frontend::FeatureExtractor extractor_;
  frontend::Map map_;
  bool has_previous_ = false;
  frontend::KeyframeId previous_ = 0;
};

}  // namespace weighted_icp::mapping
