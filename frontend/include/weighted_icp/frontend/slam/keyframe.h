#pragma once
// A frame kept in the map: its pose is optimised by the backend and its
// features anchor the landmarks.

#include <cstddef>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "weighted_icp/frontend/slam/map_point.h"

namespace weighted_icp::frontend {

struct Keyframe {
  KeyframeId id = 0;
  std::size_t frame_id = 0;
  double timestamp = 0.0;
  Eigen::Isometry3d pose_wc = Eigen::Isometry3d::Identity();
  /// The mini-map segment it belongs to; a new segment starts after tracking is lost.
  std::size_t segment = 0;
  std::vector<MapPointId> observed_points;
  /// Every feature the keyframe detected (not only those that became
  /// landmarks): what place recognition describes the keyframe by and what
  /// loop verification matches against another keyframe's landmarks.
  std::vector<cv::KeyPoint> keypoints;  // as detected (distorted image)
  cv::Mat descriptors;                  // one binary (ORB) row per keypoint, CV_8U
  std::vector<Eigen::Vector2d> pixels;  // undistorted keypoint positions
  std::vector<double> depths;           // metres at each keypoint, 0 = none
};

}  // namespace weighted_icp::frontend
