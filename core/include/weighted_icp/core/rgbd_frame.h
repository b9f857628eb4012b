#pragma once
// The one RGB-D frame type: a registered colour + depth image pair with its
// timestamp, as the TUM reader and the simulator produce it and the front end
// consumes it.

#include <cstddef>

#include <opencv2/core.hpp>

namespace weighted_icp {

/// @brief One registered colour + depth image pair.
///
/// Depth is always metric (CV_32F metres, 0 where the sensor gave no reading);
/// sources with raw 16-bit depth convert with depthFromRaw().
struct RgbdFrame {
  double timestamp = 0.0;  // seconds; for TUM data, the colour image's
  cv::Mat color;           // CV_8UC3 (BGR, as cv::imread gives it) or CV_8UC1
  cv::Mat depth;           // CV_32F metres, 0 = no reading

  /// @brief The colour image as 8-bit grey (a view of it when already grey).
  cv::Mat gray() const;
  /// @brief Pixels with a depth reading. 0 is not an error: sensors do drop
  /// whole frames, and a front end should skip such a frame, not stop.
  std::size_t validDepthPixels() const;
};

/// @brief Metric depth from a raw depth image: value / depth_factor, 0 kept as 0.
/// @param raw CV_16UC1 depth as stored (TUM PNG); other types throw std::invalid_argument
/// @param depth_factor raw value per metre, finite and > 0 (else std::invalid_argument)
cv::Mat depthFromRaw(const cv::Mat& raw, double depth_factor);

/// @brief The raw 16-bit depth image that depthFromRaw() reads back to `depth`
/// (rounded to the nearest raw unit; 0 and beyond 65535 units saturate).
/// @param depth CV_32F metres; other types throw std::invalid_argument
/// @param depth_factor raw value per metre, finite and > 0 (else std::invalid_argument)
cv::Mat depthToRaw(const cv::Mat& depth, double depth_factor);

}  // namespace weighted_icp
