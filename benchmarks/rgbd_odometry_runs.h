#pragma once
// The two trackers the benchmarks compare, on frames held in memory: the
// project's front end (any options) and OpenCV's cv::rgbd::RgbdOdometry (frame
// to frame, default parameters), each scored by ATE RMSE against the ground truth.

#include <chrono>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>
#include <opencv2/rgbd.hpp>

#include "weighted_icp/core/statistics.h"
#include "weighted_icp/frontend/perception/depth_registration.h"
#include "weighted_icp/frontend/slam/rgbd_slam.h"
#include "weighted_icp/metrics/trajectory_error.h"

namespace weighted_icp::benchmarks {

/// @brief Frames, their camera and ground truth.
struct Sequence {
  std::string name;
  PinholeCamera camera;
  std::vector<RgbdFrame> frames;
  Trajectory truth;
};

/// @brief One tracker on one sequence.
struct Run {
  double ate_rmse_m = 0.0;  // NaN when fewer than 3 poses
  std::size_t tracked = 0;  // frames with a pose
  std::vector<double> ms;   // per frame
  Trajectory estimate;      // the poses it gave
  double medianMs() const { return ms.empty() ? 0.0 : median(ms); }
  double p90Ms() const { return ms.empty() ? 0.0 : quantile(ms, 0.9); }
};

/// @brief ATE RMSE of `estimate`, NaN when it cannot be computed.
inline double ateOrNan(const Trajectory& truth, const Trajectory& estimate) {
  if (estimate.size() < 3) return std::numeric_limits<double>::quiet_NaN();
  return metrics::computeAte(truth, estimate).translation.rmse;
}

/// @brief The front end with `options`.
/// @param sequence what to track
/// @param options the front end's options (default: as wicp_rgbd_slam runs)
inline Run runFrontend(const Sequence& sequence, const frontend::RgbdSlamOptions& options = {}) {
  frontend::RgbdSlam slam(sequence.camera, options);
  Run run;
  for (const auto& frame : sequence.frames) run.ms.push_back(slam.process(frame).tracking_ms);
  slam.finish();
  run.estimate = slam.trajectory();
  run.tracked = run.estimate.size();
  run.ate_rmse_m = ateOrNan(sequence.truth, run.estimate);
  return run;
}

/// @brief cv::rgbd::RgbdOdometry frame to frame with default parameters; a
/// frame it cannot register keeps the last pose (and counts as not tracked).
/// @param sequence what to track
inline Run runOpenCvOdometry(const Sequence& sequence) {
  const cv::Mat camera_matrix(sequence.camera.cameraMatrix());
  cv::Ptr<cv::rgbd::RgbdOdometry> odometry = cv::rgbd::RgbdOdometry::create(camera_matrix);
  cv::Ptr<cv::rgbd::OdometryFrame> previous, current;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  Run run;
  Trajectory& estimate = run.estimate;
  for (const auto& frame : sequence.frames) {
    const auto start = std::chrono::steady_clock::now();
    cv::Mat gray;
    cv::cvtColor(frame.color, gray, cv::COLOR_BGR2GRAY);
    // Given the depth camera's calibration, OpenCV's user registers the depth with OpenCV's own registerDepth.
    const cv::Mat depth = sequence.camera.unregistered_depth
                              ? frontend::registerDepthWithOpenCv(frame.depth, sequence.camera)
                              : frame.depth;
    current = cv::rgbd::OdometryFrame::create(gray, depth);
    bool tracked = !previous;
    if (previous) {
      cv::Mat rt;  // maps points of the previous camera into the current one
      if ((tracked = odometry->compute(current, previous, rt))) {
        Eigen::Matrix4d motion;
        for (int r = 0; r < 4; ++r)
          for (int c = 0; c < 4; ++c) motion(r, c) = rt.at<double>(r, c);
        pose = pose * Eigen::Isometry3d(motion);
      }
    }
    run.ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    run.tracked += tracked;
    estimate.push_back({frame.timestamp, pose});
    previous = current;
  }
  run.ate_rmse_m = ateOrNan(sequence.truth, estimate);
  return run;
}

}  // namespace weighted_icp::benchmarks
