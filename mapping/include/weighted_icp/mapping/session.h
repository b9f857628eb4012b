#pragma once
// A SLAM session saved as a folder (what wicp_merge reads): the camera, the
// keyframes with their features, the landmarks with their observations, and
// every tracked frame through its reference keyframe. The format is in
// docs/mapping.md; saving is atomic (io::AtomicFolder), loading names the file
// and line of any error.

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "weighted_icp/core/camera.h"
#include "weighted_icp/core/trajectory.h"
#include "weighted_icp/frontend/slam/keyframe.h"
#include "weighted_icp/frontend/slam/map.h"
#include "weighted_icp/frontend/slam/map_point.h"
#include "weighted_icp/frontend/slam/rgbd_slam.h"

namespace weighted_icp::mapping {

/// @brief One tracked frame: its time and its pose relative to the keyframe it was tracked from.
struct SessionFrame {
  /// @brief Time stamp of the frame, seconds (as in the input sequence).
  double timestamp = 0.0;
  /// @brief The keyframe the pose is expressed in.
  frontend::KeyframeId reference_keyframe = 0;
  /// @brief Camera pose in the reference keyframe's camera frame.
  Eigen::Isometry3d pose_in_reference = Eigen::Isometry3d::Identity();
};

/// @brief Everything a session folder holds, as plain data.
struct Session {
  /// @brief The camera of the sequence.
  PinholeCamera camera;
  /// @brief Keyframes in ascending id order (ids are unique; observed_points lists the landmarks observing each).
  std::vector<frontend::Keyframe> keyframes;
  /// @brief Landmarks in ascending id order; every observation names a keyframe of the session.
  std::vector<frontend::MapPoint> points;
  /// @brief Every frame that got a pose, in processing order.
  std::vector<SessionFrame> frames;

  /// @brief Camera-to-world pose of every frame: its reference keyframe's pose times pose_in_reference.
  Trajectory trajectory() const;
  /// @brief The session as a front-end map again (for place recognition, the mini-map graph, a merge).
  /// Keyframes keep their ids, which must therefore be 0, 1, 2, ... as a SLAM run numbers them
  /// (std::invalid_argument otherwise); landmarks are numbered again in id order (the map assigns point ids;
  /// a run's ids have gaps where bundle adjustment removed points), with their observations in the same order.
  std::unique_ptr<frontend::Map> toMap() const;
  /// @brief Throws std::invalid_argument naming the first inconsistency (duplicate or unordered ids, an
  /// observation or a frame naming an unknown keyframe, feature arrays of different lengths, non-finite values).
  void validate() const;
};

/// @brief The session of a finished SLAM run (call finish() first), as its map and frames are now.
/// @param slam The SLAM.
/// @param camera Its camera.
Session captureSession(const frontend::RgbdSlam& slam, const PinholeCamera& camera);

/// @brief Writes the session folder: session.txt, camera.yaml, keyframes.txt, landmarks.txt, frames.txt.
/// Built beside `folder` and published by one rename: on any error nothing is left behind.
/// @param session The session; validated first (std::invalid_argument).
/// @param folder The folder to create.
/// @param overwrite Replace an existing non-empty folder (refused otherwise, std::runtime_error).
void saveSession(const Session& session, const std::string& folder, bool overwrite = false);

/// @brief Reads a session folder. Throws std::runtime_error for a missing folder or file (naming it) and
/// io::MapFormatError naming the file and line for a malformed or inconsistent record.
/// @param folder The folder saveSession wrote.
Session loadSession(const std::string& folder);

}  // namespace weighted_icp::mapping
