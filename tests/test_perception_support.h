#pragma once
// Real TUM frames and their ground truth for the perception tests and the
// matching benchmark: how many descriptor matches agree with the true motion.
// No GoogleTest here, so that the benchmark can include it too.

#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include "weighted_icp/io/camera.h"
#include "weighted_icp/io/tum_sequence.h"

namespace weighted_icp::testing {

struct RealSequence {
  io::TumSequence sequence;
  PinholeCamera camera;

  static RealSequence open(const std::filesystem::path& directory, int freiburg) {
    return {io::TumSequence::open(directory.string()), tumCamera(freiburg)};
  }
  RgbdFrame frame(std::size_t index) const { return sequence.loadFrame(index, camera); }
  Eigen::Isometry3d groundTruth(std::size_t index) const {
    const double timestamp = sequence.frame(index).rgb_timestamp;
    const auto pose = sequence.groundTruthAt(timestamp);
    if (!pose) throw std::runtime_error(sequence.directory() + ": no ground truth near " + std::to_string(timestamp));
    return *pose;
  }
};

struct GeometricCheck {
  int checked = 0;  // matches whose reference keypoint has a depth reading
  int inliers = 0;  // of those, within the tolerance of the true position
  double fraction() const { return checked == 0 ? 0.0 : static_cast<double>(inliers) / checked; }
};

/// Matches between a reference frame (trainIdx into reference_keypoints) and a
/// query frame (queryIdx into query_keypoints) checked against ground truth:
/// each reference keypoint is lifted with its depth, moved by the true
/// relative pose and projected, lens distortion included, into the query
/// frame; it is an inlier within tolerance_px of the matched keypoint.
inline GeometricCheck checkAgainstGroundTruth(const RealSequence& data, std::size_t reference_frame,
                                              std::size_t query_frame,
                                              const std::vector<cv::KeyPoint>& reference_keypoints,
                                              const std::vector<cv::KeyPoint>& query_keypoints,
                                              const std::vector<cv::DMatch>& matches, double tolerance_px) {
  const cv::Mat depth = data.frame(reference_frame).depth;
  const Eigen::Isometry3d reference_to_query =
      data.groundTruth(query_frame).inverse() * data.groundTruth(reference_frame);
  const cv::Matx33d camera_matrix = data.camera.cameraMatrix();
  const cv::Mat distortion = data.camera.distortionCoefficients();

  std::vector<cv::Point2f> reference_pixels;
  std::vector<float> depths;
  std::vector<cv::Point2f> query_pixels;
  for (const cv::DMatch& m : matches) {
    const cv::Point2f& pixel = reference_keypoints.at(static_cast<std::size_t>(m.trainIdx)).pt;
    const float z = depth.at<float>(cvRound(pixel.y), cvRound(pixel.x));
    if (!(z > 0.0f)) continue;
    reference_pixels.push_back(pixel);
    depths.push_back(z);
    query_pixels.push_back(query_keypoints.at(static_cast<std::size_t>(m.queryIdx)).pt);
  }
  GeometricCheck check;
  if (reference_pixels.empty()) return check;

  std::vector<cv::Point2f> normalized;
  cv::undistortPoints(reference_pixels, normalized, camera_matrix, distortion);
  std::vector<cv::Point3d> in_query;
  for (std::size_t i = 0; i < normalized.size(); ++i) {
    const Eigen::Vector3d point =
        reference_to_query * (depths[i] * Eigen::Vector3d(normalized[i].x, normalized[i].y, 1.0));
    in_query.emplace_back(point.x(), point.y(), point.z());
  }
  std::vector<cv::Point2d> projected;
  cv::projectPoints(in_query, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), camera_matrix, distortion, projected);
  for (std::size_t i = 0; i < projected.size(); ++i) {
    ++check.checked;
    const double dx = projected[i].x - query_pixels[i].x, dy = projected[i].y - query_pixels[i].y;
    if (in_query[i].z > 0.0 && std::hypot(dx, dy) <= tolerance_px) ++check.inliers;
  }
  return check;
}

}  // namespace weighted_icp::testing
