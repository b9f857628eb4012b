// The free-space check: one map's landmarks against the depths another map's keyframes measured.
#include "weighted_icp/mapping/free_space_check.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace weighted_icp::mapping {

namespace {

/// The nearest and farthest depth a keyframe measured at its features, per image cell.
class CellDepths {
 public:
  CellDepths(const frontend::Keyframe& keyframe, const PinholeCamera& camera, const FreeSpaceOptions& options)
      : cell_(std::max(1, options.cell_px)),
        columns_((camera.width + cell_ - 1) / cell_),
        rows_((camera.height + cell_ - 1) / cell_),
        nearest_(static_cast<std::size_t>(columns_ * rows_), std::numeric_limits<double>::infinity()),
        farthest_(nearest_.size(), 0.0) {
    const std::size_t n = std::min(keyframe.pixels.size(), keyframe.depths.size());
    for (std::size_t i = 0; i < n; ++i) {
      const double depth = keyframe.depths[i];
      if (!(depth > 0.0) || !std::isfinite(depth)) continue;
      const int index = indexOf(keyframe.pixels[i]);
      if (index < 0) continue;
      nearest_[static_cast<std::size_t>(index)] = std::min(nearest_[static_cast<std::size_t>(index)], depth);
      farthest_[static_cast<std::size_t>(index)] = std::max(farthest_[static_cast<std::size_t>(index)], depth);
    }
  }

  /// -1 outside the image.
  int indexOf(const Eigen::Vector2d& pixel) const {
    if (!(pixel.x() >= 0.0 && pixel.y() >= 0.0)) return -1;  // also NaN
    const int column = static_cast<int>(pixel.x()) / cell_, row = static_cast<int>(pixel.y()) / cell_;
    if (column >= columns_ || row >= rows_) return -1;
    return row * columns_ + column;
  }
  bool measured(int index) const { return std::isfinite(nearest_[static_cast<std::size_t>(index)]); }
  double nearest(int index) const { return nearest_[static_cast<std::size_t>(index)]; }
  double farthest(int index) const { return farthest_[static_cast<std::size_t>(index)]; }

 private:
  int cell_, columns_, rows_;
  std::vector<double> nearest_, farthest_;
};

}  // namespace

FreeSpaceCheck checkFreeSpace(const KeyframeSnapshot& observer, const PinholeCamera& observer_camera,
                              const KeyframeSnapshot& other, const Eigen::Isometry3d& other_in_observer,
                              const FreeSpaceOptions& options) {
  std::vector<Eigen::Vector3d> landmarks;
  landmarks.reserve(other.points.size());
  for (const auto& [id, point] : other.points) landmarks.push_back(other_in_observer * point.position);
  std::vector<std::size_t> supported(landmarks.size(), 0), violating(landmarks.size(), 0);
  for (const auto& [id, keyframe] : observer.keyframes) {
    const CellDepths cells(keyframe, observer_camera, options);
    const Eigen::Isometry3d world_to_camera = keyframe.pose_wc.inverse();
    for (std::size_t i = 0; i < landmarks.size(); ++i) {
      const Eigen::Vector3d in_camera = world_to_camera * landmarks[i];
      const double depth = in_camera.z();
      if (!(depth >= options.min_depth_m && depth <= options.max_depth_m)) continue;
      const Eigen::Vector2d pixel = observer_camera.project(in_camera);
      if (!observer_camera.inImage(pixel)) continue;
      const int cell = cells.indexOf(pixel);
      if (cell < 0 || !cells.measured(cell)) continue;
      const double margin = options.margin_m + options.margin_per_depth * depth;
      if (depth < cells.nearest(cell) - margin)
        ++violating[i];
      else if (depth <= cells.farthest(cell) + margin)
        ++supported[i];
    }
  }
  FreeSpaceCheck check;
  for (std::size_t i = 0; i < landmarks.size(); ++i) {
    check.supported_sightings += supported[i];
    check.violating_sightings += violating[i];
    if (supported[i] + violating[i] == 0) continue;
    ++check.landmarks_judged;
    if (violating[i] > supported[i]) ++check.landmarks_violating;
  }
  return check;
}

}  // namespace weighted_icp::mapping
