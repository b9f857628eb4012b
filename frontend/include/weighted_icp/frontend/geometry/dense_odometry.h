#pragma once
// OpenCV's dense RGB-D odometry (opencv_contrib rgbd: photometric, ICP or both)
// as a second opinion on frame-to-frame motion: a motion prior for PnP and a
// fallback pose when features are too weak to track (issue #11, item 3).

#include <optional>
#include <string>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <opencv2/rgbd.hpp>

#include "weighted_icp/core/camera.h"
#include "weighted_icp/core/rgbd_frame.h"

namespace weighted_icp::frontend {

/// @brief Which of OpenCV's dense odometries runs.
enum class DenseOdometryKind {
  Rgbd,    ///< cv::rgbd::RgbdOdometry: photometric error with depth (Steinbruecker et al.)
  Icp,     ///< cv::rgbd::ICPOdometry: point-to-plane ICP on depth alone
  RgbdIcp  ///< cv::rgbd::RgbdICPOdometry: both terms
};
/// @brief What the front end uses the dense motion for.
enum class DenseOdometryUse {
  Off,              ///< not at all (no cost)
  Prior,            ///< every frame: the pose guess for matching and PnP, instead of constant velocity
  Fallback,         ///< only when 3D-2D tracking fails: the pose, before the 2D-2D fallback is tried
  PriorAndFallback  ///< both
};

/// @brief "rgbd", "icp" or "rgbd-icp".
/// @param kind the kind to name
std::string toString(DenseOdometryKind kind);
/// @brief The kind named by toString; std::invalid_argument listing the names otherwise.
/// @param name the name
DenseOdometryKind parseDenseOdometryKind(const std::string& name);
/// @brief "off", "prior", "fallback" or "prior+fallback".
/// @param use the use to name
std::string toString(DenseOdometryUse use);
/// @brief The use named by toString; std::invalid_argument listing the names otherwise.
/// @param name the name
DenseOdometryUse parseDenseOdometryUse(const std::string& name);

/// @brief Dense odometry settings; OpenCV's own defaults otherwise (depth 0-4 m,
/// at most 0.15 m and 15 degrees between frames, else the motion is refused).
/// Since 2026-11-27 the fallback with both terms is the default: where features fail (low light, blur) depth still
/// registers the frame, and OpenCV's photometric term alone finds too few gradients in a dark image
/// (docs/frontend_generalisation.md, "The dense fallback on by default"). It costs nothing on frames 3D-2D poses.
struct DenseOdometryOptions {
  DenseOdometryUse use = DenseOdometryUse::Fallback;
  DenseOdometryKind kind = DenseOdometryKind::RgbdIcp;
};

/// @brief Motion of the current frame relative to a reference frame (the last
/// one the front end posed), computed lazily: a frame that is never asked
/// about costs only its image headers. Not thread-safe; deterministic (OpenCV's
/// dense odometry has no random steps).
class DenseOdometry {
 public:
  /// @brief Creates the OpenCV odometry for the camera (distortion is ignored, as OpenCV's odometry does).
  /// @param camera intrinsics of the colour image, to which depth is registered
  /// @param kind which odometry
  DenseOdometry(const PinholeCamera& camera, DenseOdometryKind kind);

  /// @brief The frame motions are measured for from now on (its motion, if computed, is forgotten).
  /// Throws std::invalid_argument when depth is not CV_32F of the colour image's size or gray not of that size.
  /// @param frame the frame being tracked
  /// @param gray  its grey image (RgbdFrame::gray), which the caller has already: kept, copied only when it shares
  ///              the colour image's pixels (a grey input image the caller may overwrite)
  void setCurrent(const RgbdFrame& frame, const cv::Mat& gray);
  /// @brief The current frame becomes the reference (it got a pose).
  void acceptCurrent();
  /// @brief No reference any more (e.g. after tracking was lost).
  void reset();
  /// @brief Pose of the current camera in the reference camera (T_ref_cur); empty without a
  /// reference or current frame, or when OpenCV cannot register them (too little valid depth,
  /// or a motion beyond its limits). Computed once per current frame.
  std::optional<Eigen::Isometry3d> motionFromReference();

 private:
  cv::Ptr<cv::rgbd::Odometry> odometry_;
  cv::Ptr<cv::rgbd::OdometryFrame> reference_;
  cv::Ptr<cv::rgbd::OdometryFrame> current_;
  bool computed_ = false;
  std::optional<Eigen::Isometry3d> motion_;
};

}  // namespace weighted_icp::frontend
