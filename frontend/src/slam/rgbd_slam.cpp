#include "weighted_icp/frontend/slam/rgbd_slam.h"

#include <chrono>
#include <ctime>

#include "weighted_icp/frontend/slam/landmark_conversion.h"

namespace weighted_icp::frontend {

namespace {
/// CPU time consumed by the calling thread, in milliseconds.
double threadCpuMs() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) * 1e3 + static_cast<double>(now.tv_nsec) * 1e-6;
}

/// The backend weighs depth with the front end's noise model: one sensor, one model.
BackendOptions withFrontendNoise(BackendOptions backend, const FrontendOptions& frontend) {
  backend.bundle_adjustment.noise = frontend.depth_noise;
  return backend;
}
}  // namespace

RgbdSlam::RgbdSlam(const PinholeCamera& camera, const RgbdSlamOptions& options)
    : camera_(camera),
      backend_options_(withFrontendNoise(options.backend, options.frontend)),
      backend_(map_, camera, backend_options_),
      frontend_(map_, backend_, camera, options.frontend),
      minimap_builder_(options.minimap_keyframes) {}

const FrameRecord& RgbdSlam::process(const RgbdFrame& image) {
  FrameRecord record;
  record.timestamp = image.timestamp;
  const auto start = std::chrono::steady_clock::now();
  const double cpu_start = threadCpuMs();
  record.result = frontend_.track(image);
  record.tracking_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  record.tracking_cpu_ms = threadCpuMs() - cpu_start;
  frames_.push_back(record);
  return frames_.back();
}

void RgbdSlam::finish() { backend_.flush(); }

bool RgbdSlam::bundleAdjustWholeSegment(int max_iterations) {
  backend_.flush();  // no local window is written back over it
  BackendOptions options = backend_options_;
  options.bundle_adjustment.max_iterations = max_iterations;
  return optimizeLatestKeyframes(map_, camera_, options, map_.keyframeCount());
}

LandmarkMap RgbdSlam::sessionMap() const { return toLandmarkMap(map_); }

Trajectory RgbdSlam::trajectory() const {
  Trajectory trajectory;
  for (const auto& frame : frames_) {
    if (!frame.result.hasPose()) continue;
    // Each frame rides on its reference keyframe, as refined by the backend.
    const auto reference = map_.keyframePose(frame.result.reference_keyframe);
    trajectory.push_back(
        {frame.timestamp, reference ? *reference * frame.result.pose_in_reference : frame.result.pose_wc});
  }
  return trajectory;
}

}  // namespace weighted_icp::frontend
