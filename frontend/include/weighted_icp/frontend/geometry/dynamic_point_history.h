#pragma once
// The front-end paper's dynamic-point distance function (its Eq. 6) in normal
// tracking: each tracked point's epipolar distance between consecutive
// observations, compared with the earlier values of the same point.

#include <cstddef>
#include <cstdint>
#include <deque>
#include <string>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "weighted_icp/core/camera.h"

namespace weighted_icp::frontend {

/// @brief Which distance flags moving points in 3D-2D tracking.
enum class DynamicDistanceKind {
  Displacement,     // today: 3D displacement against the depth noise (flagDynamicByDisplacement)
  EpipolarHistory,  // the paper's Eq. 6: epipolar distance compared along the sequence
  Both              // flagged by either
};

/// @brief "displacement", "epipolar-history", "both"; throws std::invalid_argument otherwise.
/// @param name the command-line spelling.
DynamicDistanceKind parseDynamicDistanceKind(const std::string& name);
/// @brief The name parseDynamicDistanceKind reads. @param kind the distance.
std::string dynamicDistanceKindName(DynamicDistanceKind kind);

/// @brief Thresholds of DynamicPointHistory.
struct DynamicPointHistoryOptions {
  /// Earlier distances kept per point; the comparison is with their median.
  std::size_t history = 5;
  /// Flag when d_k exceeds the median of the earlier distances by this much (pixels).
  double max_increase_px = 2.0;
  /// A point seen for the first time has no earlier value: flagged above this.
  double max_first_px = 3.0;
  /// A point not seen for this many frames starts its history again.
  std::size_t forget_after_frames = 5;
};

/// @brief Per tracked point, the Eq. 6 distance d_k and its earlier values.
///
/// Reading of Eq. 6 (garbled in the extracted text): the displacement
/// function is d = |D2^T F D1| / sqrt(v1^2 + v2^2), the distance of the point's
/// pixel D2 in the current frame to the epipolar line v = F D1 of its pixel D1
/// in the frame it was last seen in (F from the estimated motion between the
/// two), and Delta d_k = d_k - d_{k-1} is compared along the sequence ("the
/// distance function is computed and compared to the previously measured
/// value"). A static point keeps d near the pixel noise; one that starts to
/// move raises it. The earlier values enter through their median, so one noisy
/// frame does not flag a point, and only unflagged values are kept, so a point
/// that keeps moving stays flagged. Deterministic; no threads.
class DynamicPointHistory {
 public:
  /// @brief Checks the options. @param options see DynamicPointHistoryOptions.
  /// Throws std::invalid_argument for options out of range.
  explicit DynamicPointHistory(DynamicPointHistoryOptions options = {});

  /// @brief Flags the points of one frame and records their observations.
  /// @param frame index of the frame (increasing).
  /// @param ids the points' ids (one per observation).
  /// @param pixels their undistorted pixels in this frame.
  /// @param pose_wc this frame's estimated camera-to-world pose.
  /// @param camera intrinsics for the fundamental matrix.
  /// Returns one flag per point. Throws std::invalid_argument for mismatched sizes.
  std::vector<bool> update(std::size_t frame, const std::vector<std::uint64_t>& ids,
                           const std::vector<Eigen::Vector2d>& pixels, const Eigen::Isometry3d& pose_wc,
                           const PinholeCamera& camera);

  /// @brief The last distance d_k of a point, NaN if none. @param id the point.
  double lastDistance(std::uint64_t id) const;
  /// @brief Points with a history.
  std::size_t size() const { return points_.size(); }

 private:
  struct Seen {
    bool observed = false;  // pixel and pose hold the last observation
    std::size_t frame = 0;
    Eigen::Vector2d pixel = Eigen::Vector2d::Zero();
    Eigen::Isometry3d pose_wc = Eigen::Isometry3d::Identity();
    std::deque<double> distances;
  };
  DynamicPointHistoryOptions options_;
  std::unordered_map<std::uint64_t, Seen> points_;
};

}  // namespace weighted_icp::frontend
