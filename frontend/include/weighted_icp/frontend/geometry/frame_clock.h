#pragma once
// How many frame periods passed between two timestamps. The period is the median of the recent intervals, so a
// sensor's jitter (TUM's Kinect: 28-36 ms around 32) rounds away while a dropped frame counts as two periods.

#include <cstddef>
#include <deque>
#include <optional>

namespace weighted_icp::frontend {

/// @brief The sensor's frame period, learnt from the timestamps of the frames as they come, and the whole number of
/// periods between two timestamps.
class FrameClock {
 public:
  /// @brief How many recent intervals the period is the median of.
  static constexpr std::size_t kWindow = 31;
  /// @brief The most periods periodsBetween() reports: a longer gap is a break, not a motion to extrapolate.
  static constexpr int kMaxPeriods = 1000;

  /// @brief Records the timestamp of the next frame. A non-finite timestamp, or one not after the last, adds no
  /// interval (sequences without timestamps count every frame as one period).
  /// @param timestamp seconds
  void tick(double timestamp);
  /// @brief The median of the last kWindow intervals; empty before two increasing timestamps.
  std::optional<double> period() const;
  /// @brief The whole number of periods from t0 to t1, in [1, kMaxPeriods]; 1 when the period is unknown or the
  /// timestamps are not finite and increasing.
  /// @param t0 the earlier timestamp, seconds
  /// @param t1 the later timestamp, seconds
  int periodsBetween(double t0, double t1) const;

 private:
  std::deque<double> intervals_;
  std::optional<double> last_;
};

}  // namespace weighted_icp::frontend
