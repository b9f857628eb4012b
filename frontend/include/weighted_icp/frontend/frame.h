#pragma once
// One RGB-D frame as the tracker sees it: its features, their depths and the
// camera pose estimated for it.

#include <cstddef>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

namespace weighted_icp::frontend {

/// The input of the front end: one registered colour + depth image pair.
struct RgbdImage {
  double timestamp = 0.0;
  cv::Mat color;  // CV_8UC3 (BGR) or CV_8UC1
  cv::Mat depth;  // CV_32F metres, 0 where invalid
};

struct Frame {
  std::size_t id = 0;
  double timestamp = 0.0;
  std::vector<cv::KeyPoint> keypoints;  // as detected (distorted image)
  cv::Mat descriptors;                  // one ORB row per keypoint
  std::vector<Eigen::Vector2d> pixels;  // undistorted keypoint positions
  std::vector<double> depths;           // metres at each keypoint, 0 = none
  Eigen::Isometry3d pose_wc = Eigen::Isometry3d::Identity();  // camera-to-world

  std::size_t size() const { return keypoints.size(); }
  bool hasDepth(std::size_t i) const { return depths[i] > 0.0; }
};

}  // namespace weighted_icp::frontend
