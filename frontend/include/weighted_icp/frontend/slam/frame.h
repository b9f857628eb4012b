#pragma once
// One RGB-D frame as the tracker sees it: its features, their depths and the
// camera pose estimated for it.

#include <algorithm>
#include <cstddef>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "weighted_icp/core/rgbd_frame.h"

namespace weighted_icp::frontend {

/// The input of the front end is core's RgbdFrame; this name keeps
/// frontend::RgbdImage working for one release.
using RgbdImage = weighted_icp::RgbdFrame;

struct Frame {
  std::size_t id = 0;
  double timestamp = 0.0;
  std::vector<cv::KeyPoint> keypoints;                        // as detected (distorted image)
  cv::Mat descriptors;                                        // one ORB row per keypoint
  std::vector<Eigen::Vector2d> pixels;                        // undistorted keypoint positions
  std::vector<double> depths;                                 // metres at each keypoint, 0 = none
  Eigen::Isometry3d pose_wc = Eigen::Isometry3d::Identity();  // camera-to-world

  std::size_t size() const { return keypoints.size(); }
  bool hasDepth(std::size_t i) const { return depths[i] > 0.0; }
  /// How many features have a depth.
  std::size_t withDepth() const {
    return static_cast<std::size_t>(std::count_if(depths.begin(), depths.end(), [](double d) { return d > 0.0; }));
  }
};

}  // namespace weighted_icp::frontend
