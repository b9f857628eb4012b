#pragma once
// The landmark map of a feature-based visual SLAM: camera poses of the frames
// and, per landmark, its position, position covariance and every observation.
// This is the model the weights are derived from; io/ reads and writes it.

#include <cstddef>
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace weighted_icp {

using FrameId = std::uint64_t;
using LandmarkId = std::uint64_t;

/// One sighting of a landmark: the frame that saw it and where (pixels).
struct Observation {
  FrameId frame_id = 0;
  double u = 0.0;
  double v = 0.0;
};

struct Landmark {
  LandmarkId id = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  std::vector<Observation> observations;
};

/// What the weight strategies see of a landmark (see weight_strategies.h).
struct LandmarkMetrics {
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  std::size_t num_observations = 0;
  /// Mean Euclidean distance from the landmark to the centres of the cameras
  /// that observed it; 0 when it has no observations.
  double mean_observation_distance = 0.0;
};

class LandmarkMap {
 public:
  /// Camera-to-world poses, keyed (and so ordered) by frame id.
  std::map<FrameId, Eigen::Isometry3d> frames;
  std::vector<Landmark> landmarks;

  /// Throws std::out_of_range naming the landmark and frame when an
  /// observation refers to a frame the map does not have.
  double meanObservationDistance(const Landmark& landmark) const;
  LandmarkMetrics metrics(const Landmark& landmark) const;

  /// Landmarks with at least `min_observations` observations; frames kept.
  LandmarkMap withMinObservations(std::size_t min_observations) const;

  /// The mini-map of frames [first, last]: those frames, and every landmark
  /// seen by at least one of them with only the observations from them (so
  /// observation counts and mean distances are those of the mini-map).
  /// Position and covariance are kept as the session estimated them.
  LandmarkMap miniMap(FrameId first, FrameId last) const;

  /// Consecutive mini-maps of `frames_per_minimap` frames each, in frame-id
  /// order; the last one may be shorter.
  std::vector<LandmarkMap> splitIntoMiniMaps(std::size_t frames_per_minimap) const;

  /// Two maps with every frame and alternate landmarks (even, odd positions):
  /// disjoint point sets over the same scene, whose true relation is the
  /// identity. The standard test pair for registration on one session map,
  /// since mini-maps of distant frame ranges may share little of the scene.
  std::pair<LandmarkMap, LandmarkMap> alternateHalves() const;

  /// Applies a rigid transform to frame poses and landmark positions, and
  /// rotates the covariances with it.
  void transform(const Eigen::Isometry3d& motion);

  /// Moves the map into its first frame's camera frame, as a SLAM without gravity writes it, and returns that
  /// camera's pose before the move (the former world's z in the camera's frame is its linear().transpose() * z).
  /// A map without frames throws std::invalid_argument.
  Eigen::Isometry3d toFirstCameraFrame();
};

/// @brief Deals out the landmarks both maps hold (the same id) by id parity: `a` keeps the even ids, `b` the odd
/// ones, so no landmark is in both (two mini-maps of one session sharing no point, as wicp_global_sweep --disjoint
/// makes them).
/// @param a  the first map; keeps its landmarks `b` lacks and the shared even ids
/// @param b  the second map; keeps its landmarks `a` lacks and the shared odd ids
void dealOutSharedLandmarks(LandmarkMap& a, LandmarkMap& b);

}  // namespace weighted_icp
