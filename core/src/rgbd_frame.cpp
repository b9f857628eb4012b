// The RGB-D frame type and the raw <-> metric depth conversions.
#include "weighted_icp/core/rgbd_frame.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>

namespace weighted_icp {

namespace {

void requireDepthFactor(double depth_factor) {
  if (!(std::isfinite(depth_factor) && depth_factor > 0.0))
    throw std::invalid_argument("the depth factor must be a finite number > 0, not " + std::to_string(depth_factor));
}

}  // namespace

cv::Mat RgbdFrame::gray() const {
  if (color.channels() == 1) return color;
  cv::Mat result;
  cv::cvtColor(color, result, cv::COLOR_BGR2GRAY);
  return result;
}

std::size_t RgbdFrame::validDepthPixels() const {
  if (depth.empty()) return 0;
  // NaN compares false: only positive readings count.
  return static_cast<std::size_t>(cv::countNonZero(depth > 0.0f));
}

cv::Mat depthFromRaw(const cv::Mat& raw, double depth_factor) {
  requireDepthFactor(depth_factor);
  if (raw.type() != CV_16UC1) throw std::invalid_argument("raw depth must be CV_16UC1");
  cv::Mat metres;
  raw.convertTo(metres, CV_32F, 1.0 / depth_factor);  // 0 (no reading) stays 0
  return metres;
}

cv::Mat depthToRaw(const cv::Mat& depth, double depth_factor) {
  requireDepthFactor(depth_factor);
  if (depth.type() != CV_32FC1) throw std::invalid_argument("metric depth must be CV_32FC1");
  cv::Mat raw;
  depth.convertTo(raw, CV_16U, depth_factor);  // rounds to nearest, saturates
  return raw;
}

}  // namespace weighted_icp
