// RgbdSlam composed with the loop closer.
#include "weighted_icp/mapping/loop_closing_slam.h"

#include <stdexcept>

namespace weighted_icp::mapping {

namespace {

/// The loop closer's options, with this run's camera for the odometry information from tracking when asked.
LoopClosingOptions loopClosingOptions(const PinholeCamera& camera, const LoopClosingSlamOptions& options) {
  LoopClosingOptions closing = options.loop_closing;
  if (options.odometry_from_tracking && !closing.tracking_camera) {
    closing.tracking_camera = camera;
    closing.tracking_camera->distortion = {};  // keyframe pixels are undistorted
  }
  return closing;
}

}  // namespace

LoopClosingSlam::LoopClosingSlam(const PinholeCamera& camera, LoopDetector detector,
                                 const LoopClosingSlamOptions& options)
    : slam_(camera, options.slam), global_bundle_adjustment_iterations_(options.global_bundle_adjustment_iterations) {
  if (options.loop_closure)
    loop_closer_ = std::make_unique<LoopCloser>(slam_.map(), std::move(detector), loopClosingOptions(camera, options));
}

const frontend::FrameRecord& LoopClosingSlam::process(const RgbdFrame& image) {
  const frontend::FrameRecord& record = slam_.process(image);
  // A keyframe's pose is expressed relative to itself: its reference is its id.
  if (loop_closer_ && record.result.keyframe) loop_closer_->keyframeInserted(record.result.reference_keyframe);
  return record;
}

void LoopClosingSlam::finish() {
  slam_.finish();
  if (loop_closer_) {
    loop_closer_->flush();
    slam_.applyPendingCorrection();
  }
  if (global_bundle_adjustment_iterations_ > 0 && !global_bundle_adjusted_)
    global_bundle_adjusted_ = slam_.bundleAdjustWholeSegment(global_bundle_adjustment_iterations_);
}

LoopClosingStats LoopClosingSlam::loopStats() const {
  return loop_closer_ ? loop_closer_->stats() : LoopClosingStats{};
}

std::vector<LoopConstraint> LoopClosingSlam::acceptedLoops() const {
  return loop_closer_ ? loop_closer_->acceptedLoops() : std::vector<LoopConstraint>{};
}

}  // namespace weighted_icp::mapping
