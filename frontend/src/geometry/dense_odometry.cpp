// OpenCV's dense RGB-D odometry wrapped for the front end: lazily computed motion to the last posed frame.
#include "weighted_icp/frontend/geometry/dense_odometry.h"

#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "weighted_icp/core/named_values.h"

namespace weighted_icp::frontend {

std::string toString(DenseOdometryKind kind) {
  switch (kind) {
    case DenseOdometryKind::Rgbd: return "rgbd";
    case DenseOdometryKind::Icp: return "icp";
    case DenseOdometryKind::RgbdIcp: return "rgbd-icp";
  }
  return "unknown";
}

DenseOdometryKind parseDenseOdometryKind(const std::string& name) {
  return parseNamedValue(
      name, {DenseOdometryKind::Rgbd, DenseOdometryKind::Icp, DenseOdometryKind::RgbdIcp},
      [](auto value) { return toString(value); }, "dense odometry kind");
}

std::string toString(DenseOdometryUse use) {
  switch (use) {
    case DenseOdometryUse::Off: return "off";
    case DenseOdometryUse::Prior: return "prior";
    case DenseOdometryUse::Fallback: return "fallback";
    case DenseOdometryUse::PriorAndFallback: return "prior+fallback";
  }
  return "unknown";
}

DenseOdometryUse parseDenseOdometryUse(const std::string& name) {
  return parseNamedValue(
      name,
      {DenseOdometryUse::Off, DenseOdometryUse::Prior, DenseOdometryUse::Fallback, DenseOdometryUse::PriorAndFallback},
      [](auto value) { return toString(value); }, "dense odometry use");
}

DenseOdometry::DenseOdometry(const PinholeCamera& camera, DenseOdometryKind kind) {
  const cv::Mat camera_matrix(camera.cameraMatrix());
  switch (kind) {
    case DenseOdometryKind::Rgbd: odometry_ = cv::rgbd::RgbdOdometry::create(camera_matrix); break;
    case DenseOdometryKind::Icp: odometry_ = cv::rgbd::ICPOdometry::create(camera_matrix); break;
    case DenseOdometryKind::RgbdIcp: odometry_ = cv::rgbd::RgbdICPOdometry::create(camera_matrix); break;
  }
}

void DenseOdometry::setCurrent(const RgbdFrame& frame, const cv::Mat& gray) {
  if (frame.color.empty() || frame.depth.type() != CV_32F || frame.depth.size() != frame.color.size() ||
      gray.size() != frame.color.size())
    throw std::invalid_argument("DenseOdometry: frame at " + std::to_string(frame.timestamp) +
                                " needs a colour image, its grey image and CV_32F depth of its size");
  // The odometry keeps its pyramids in the frame object, so the reference's are built once. The images outlive the
  // caller's frame: the depth and a grey image that is the caller's own colour buffer are copied.
  const cv::Mat own_gray = gray.data == frame.color.data ? gray.clone() : gray;
  current_ = cv::rgbd::OdometryFrame::create(own_gray, frame.depth.clone());
  computed_ = false;
  motion_.reset();
}

void DenseOdometry::acceptCurrent() {
  if (current_) reference_ = current_;
  computed_ = false;
  motion_.reset();
}

void DenseOdometry::reset() {
  reference_.release();
  computed_ = false;
  motion_.reset();
}

std::optional<Eigen::Isometry3d> DenseOdometry::motionFromReference() {
  if (computed_) return motion_;
  computed_ = true;
  if (!reference_ || !current_ || reference_ == current_) return std::nullopt;
  cv::Mat rt;  // maps points of the current camera into the reference one: T_ref_cur
  bool ok = false;
  try {
    ok = odometry_->compute(current_, reference_, rt);
  } catch (const cv::Exception&) {
    ok = false;  // e.g. no valid depth at all in one of the frames
  }
  if (!ok || rt.rows != 4 || rt.cols != 4) return std::nullopt;
  Eigen::Matrix4d matrix;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) matrix(r, c) = rt.at<double>(r, c);
  if (!matrix.allFinite()) return std::nullopt;
  Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
  motion.linear() = Eigen::Quaterniond(Eigen::Matrix3d(matrix.topLeftCorner<3, 3>())).normalized().toRotationMatrix();
  motion.translation() = matrix.topRightCorner<3, 1>();
  motion_ = motion;
  return motion_;
}

}  // namespace weighted_icp::frontend
