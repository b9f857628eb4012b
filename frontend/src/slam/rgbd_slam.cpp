#include "weighted_icp/frontend/rgbd_slam.h"

#include <chrono>

namespace weighted_icp::frontend {

RgbdSlam::RgbdSlam(const io::PinholeCamera& camera, const RgbdSlamOptions& options)
    : backend_(map_, camera, options.backend),
      frontend_(map_, backend_, camera, options.frontend),
      minimap_builder_(options.minimap_keyframes) {}

const FrameRecord& RgbdSlam::process(const RgbdImage& image) {
  FrameRecord record;
  record.timestamp = image.timestamp;
  const auto start = std::chrono::steady_clock::now();
  record.result = frontend_.track(image);
  record.tracking_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  frames_.push_back(record);
  return frames_.back();
}

void RgbdSlam::finish() { backend_.flush(); }

io::Trajectory RgbdSlam::trajectory() const {
  io::Trajectory trajectory;
  for (const auto& frame : frames_)
    if (frame.result.hasPose()) trajectory.push_back({frame.timestamp, frame.result.pose_wc});
  return trajectory;
}

}  // namespace weighted_icp::frontend
