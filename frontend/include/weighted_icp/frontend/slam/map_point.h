#pragma once
// A landmark of the SLAM map: position, its uncertainty and every keyframe
// that observed it, which is what the weighted ICP's confidences come from.

#include <cstddef>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace weighted_icp::frontend {

using KeyframeId = std::size_t;
using MapPointId = std::size_t;

struct MapPointObservation {
  KeyframeId keyframe = 0;
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();  // undistorted
  double depth = 0.0;                               // metres, 0 = none
};

struct MapPoint {
  MapPointId id = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();
  cv::Mat descriptor;  // of the latest observation: appearance drifts with viewpoint
  std::vector<MapPointObservation> observations;
};

}  // namespace weighted_icp::frontend
