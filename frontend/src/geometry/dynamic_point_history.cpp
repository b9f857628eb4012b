// DynamicPointHistory: Eq. 6 epipolar distances per point, compared with their own earlier values.

#include "weighted_icp/frontend/geometry/dynamic_point_history.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>

#include "weighted_icp/core/named_values.h"
#include "weighted_icp/core/statistics.h"
#include "weighted_icp/frontend/geometry/dynamic_point_filter.h"

namespace weighted_icp::frontend {

DynamicDistanceKind parseDynamicDistanceKind(const std::string& name) {
  return parseNamedValue(
      name, {DynamicDistanceKind::Displacement, DynamicDistanceKind::EpipolarHistory, DynamicDistanceKind::Both},
      dynamicDistanceKindName, "dynamic distance");
}

std::string dynamicDistanceKindName(DynamicDistanceKind kind) {
  switch (kind) {
    case DynamicDistanceKind::Displacement: return "displacement";
    case DynamicDistanceKind::EpipolarHistory: return "epipolar-history";
    case DynamicDistanceKind::Both: return "both";
  }
  return "unknown";
}

DynamicPointHistory::DynamicPointHistory(DynamicPointHistoryOptions options) : options_(options) {
  if (options_.history < 1) throw std::invalid_argument("DynamicPointHistory: history must be >= 1");
  if (!(options_.max_increase_px > 0.0) || !(options_.max_first_px > 0.0))
    throw std::invalid_argument("DynamicPointHistory: max_increase_px and max_first_px must be > 0");
  if (options_.forget_after_frames < 1)
    throw std::invalid_argument("DynamicPointHistory: forget_after_frames must be >= 1");
}

std::vector<bool> DynamicPointHistory::update(std::size_t frame, const std::vector<std::uint64_t>& ids,
                                              const std::vector<Eigen::Vector2d>& pixels,
                                              const Eigen::Isometry3d& pose_wc, const PinholeCamera& camera) {
  if (ids.size() != pixels.size())
    throw std::invalid_argument("DynamicPointHistory::update: " + std::to_string(ids.size()) + " ids but " +
                                std::to_string(pixels.size()) + " pixels");
  std::vector<bool> flags(ids.size(), false);
  // Most points were last seen in the same few frames: one fundamental matrix per earlier frame.
  std::map<std::size_t, Eigen::Matrix3d> fundamentals;
  for (std::size_t i = 0; i < ids.size(); ++i) {
    Seen& seen = points_[ids[i]];
    const bool known = seen.observed && seen.frame < frame && frame - seen.frame <= options_.forget_after_frames;
    if (known) {
      // Distance of the pixel to the epipolar line of the earlier pixel; NaN without translation.
      auto fundamental = fundamentals.find(seen.frame);
      if (fundamental == fundamentals.end())
        fundamental =
            fundamentals.emplace(seen.frame, fundamentalMatrix(seen.pose_wc.inverse() * pose_wc, camera)).first;
      const double d = distanceToLine(fundamental->second * seen.pixel.homogeneous(), pixels[i]);
      if (std::isfinite(d)) {
        if (seen.distances.empty()) {
          flags[i] = d > options_.max_first_px;
        } else {
          const double usual = median(std::vector<double>(seen.distances.begin(), seen.distances.end()));
          flags[i] = d - usual > options_.max_increase_px;
        }
        // Only the values of a point judged static become its reference: one
        // that keeps moving stays flagged instead of making its motion the norm.
        if (!flags[i]) seen.distances.push_back(d);
        if (seen.distances.size() > options_.history) seen.distances.pop_front();
      }
    } else {
      seen.distances.clear();
    }
    seen.observed = true;
    seen.frame = frame;
    seen.pixel = pixels[i];
    seen.pose_wc = pose_wc;
  }
  // Points unseen for long are forgotten: the map stays the size of what is tracked.
  for (auto it = points_.begin(); it != points_.end();)
    it = frame - it->second.frame > options_.forget_after_frames ? points_.erase(it) : std::next(it);
  return flags;
}

double DynamicPointHistory::lastDistance(std::uint64_t id) const {
  const auto it = points_.find(id);
  if (it == points_.end() || it->second.distances.empty()) return std::numeric_limits<double>::quiet_NaN();
  return it->second.distances.back();
}

}  // namespace weighted_icp::frontend
