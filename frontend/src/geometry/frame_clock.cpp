#include "weighted_icp/frontend/geometry/frame_clock.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "weighted_icp/core/statistics.h"

namespace weighted_icp::frontend {

void FrameClock::tick(double timestamp) {
  if (!std::isfinite(timestamp) || (last_ && timestamp <= *last_)) return;
  if (last_) {
    intervals_.push_back(timestamp - *last_);
    if (intervals_.size() > kWindow) intervals_.pop_front();
  }
  last_ = timestamp;
}

std::optional<double> FrameClock::period() const {
  if (intervals_.empty()) return std::nullopt;
  return median(std::vector<double>(intervals_.begin(), intervals_.end()));
}

int FrameClock::periodsBetween(double t0, double t1) const {
  const std::optional<double> typical = period();
  if (!typical || !std::isfinite(t0) || !std::isfinite(t1) || t1 <= t0) return 1;
  const double periods = std::round((t1 - t0) / *typical);
  return static_cast<int>(std::clamp(periods, 1.0, static_cast<double>(kMaxPeriods)));
}

}  // namespace weighted_icp::frontend
