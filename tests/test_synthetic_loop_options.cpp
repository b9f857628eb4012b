// The synthetic sequence's loop options: frames_per_loop brings the camera
// back to its start, repeated_texture changes the images but not the path,
// and both leave the default sequence as it was; a calibration error changes
// only the camera the tracker is given, room_scale the room's floor plan and the path.

#include <cmath>

#include <gtest/gtest.h>

#include "weighted_icp/simulation/rgbd_sequence.h"

namespace weighted_icp::simulation {
namespace {

/// Two frames of 160 x 120 pixels: enough to compare images and cameras, quick to render.
SyntheticRgbdOptions twoSmallFrames() {
  SyntheticRgbdOptions options;
  options.frames = 2;
  options.camera.width = 160;
  options.camera.height = 120;
  options.camera.fx = options.camera.fy = 130.0;
  options.camera.cx = 80.0;
  options.camera.cy = 60.0;
  return options;
}

TEST(SyntheticLoopOptions, FramesPerLoopBringsTheCameraBack) {
  SyntheticRgbdOptions options;
  options.frames = 400;
  options.frames_per_loop = 180.0;
  const SyntheticRgbdSequence loop(options);
  // Back over its start after one loop (hand tremor of a few centimetres aside), far from it half way.
  EXPECT_LT((loop.cameraToWorld(180).translation() - loop.cameraToWorld(0).translation()).norm(), 0.1);
  EXPECT_GT((loop.cameraToWorld(90).translation() - loop.cameraToWorld(0).translation()).norm(), 1.0);
  // The default keeps its 800 frames per loop: frame 180 of the default path is elsewhere.
  options.frames_per_loop = SyntheticRgbdOptions{}.frames_per_loop;
  EXPECT_DOUBLE_EQ(options.frames_per_loop, 800.0);
  const SyntheticRgbdSequence slow(options);
  EXPECT_GT((slow.cameraToWorld(180).translation() - slow.cameraToWorld(0).translation()).norm(), 0.5);
  options.frames_per_loop = 5.0;
  EXPECT_THROW(SyntheticRgbdSequence{options}, std::invalid_argument);
}

TEST(SyntheticLoopOptions, RepeatedTextureChangesImagesNotPoses) {
  SyntheticRgbdOptions options = twoSmallFrames();
  const SyntheticRgbdFrame plain = SyntheticRgbdSequence(options).frame(1);
  options.repeated_texture = true;
  const SyntheticRgbdFrame aliased = SyntheticRgbdSequence(options).frame(1);
  EXPECT_TRUE(plain.camera_to_world.isApprox(aliased.camera_to_world));
  EXPECT_GT(cv::norm(plain.rgbd.color, aliased.rgbd.color, cv::NORM_L1) / plain.rgbd.color.total(), 5.0);
  // Geometry is the same: depth differs only by its noise, which is a hash of the pixel (so not at all).
  EXPECT_EQ(cv::norm(plain.rgbd.depth, aliased.rgbd.depth, cv::NORM_INF), 0.0);
}

TEST(SyntheticLoopOptions, CalibrationErrorChangesTheTrackersCameraNotTheImages) {
  SyntheticRgbdOptions options = twoSmallFrames();
  const SyntheticRgbdSequence calibrated(options);
  const PinholeCamera exact = calibrated.trackerCamera();
  EXPECT_EQ(exact.fx, options.camera.fx);
  EXPECT_EQ(exact.cy, options.camera.cy);

  options.focal_length_error = 0.015;
  options.principal_point_error_x_px = 1.0;
  options.principal_point_error_y_px = -4.0;
  const SyntheticRgbdSequence uncalibrated(options);
  const PinholeCamera wrong = uncalibrated.trackerCamera();
  EXPECT_DOUBLE_EQ(wrong.fx, 130.0 * 1.015);
  EXPECT_DOUBLE_EQ(wrong.fy, 130.0 * 1.015);
  EXPECT_DOUBLE_EQ(wrong.cx, 81.0);
  EXPECT_DOUBLE_EQ(wrong.cy, 56.0);
  EXPECT_EQ(wrong.width, options.camera.width);
  EXPECT_EQ(wrong.depth_factor, options.camera.depth_factor);
  // The images and the truth are those of the true camera: only what the tracker is told changes.
  const SyntheticRgbdFrame a = calibrated.frame(1), b = uncalibrated.frame(1);
  EXPECT_TRUE(a.camera_to_world.isApprox(b.camera_to_world));
  EXPECT_EQ(cv::norm(a.rgbd.color, b.rgbd.color, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(a.rgbd.depth, b.rgbd.depth, cv::NORM_INF), 0.0);

  for (const double bad : {0.25, -0.3, std::nan("")}) {
    options.focal_length_error = bad;
    EXPECT_THROW(SyntheticRgbdSequence{options}, std::invalid_argument) << bad;
  }
  options.focal_length_error = 0.0;
  options.principal_point_error_x_px = 30.0;  // more than a sixth of 160 px
  EXPECT_THROW(SyntheticRgbdSequence{options}, std::invalid_argument);
}

TEST(SyntheticLoopOptions, RoomScaleStretchesTheFloorPlanAndThePath) {
  SyntheticRgbdOptions options;
  options.frames = 200;
  options.frames_per_loop = 180.0;
  const SyntheticRgbdSequence office(options);
  options.room_scale = 2.0;
  const SyntheticRgbdSequence hall(options);
  EXPECT_DOUBLE_EQ(hall.roomSize().x(), 2.0 * office.roomSize().x());
  EXPECT_DOUBLE_EQ(hall.roomSize().y(), 2.0 * office.roomSize().y());
  EXPECT_DOUBLE_EQ(hall.roomSize().z(), office.roomSize().z());
  ASSERT_EQ(hall.furniture().size(), office.furniture().size());
  for (std::size_t k = 0; k < hall.furniture().size(); ++k) {
    EXPECT_TRUE(hall.furniture()[k].center.head<2>().isApprox(2.0 * office.furniture()[k].center.head<2>()));
    EXPECT_TRUE(hall.furniture()[k].size.isApprox(office.furniture()[k].size));
  }
  // The same path, twice as wide, at the same height; still a loop.
  for (const std::size_t i : {0, 45, 90}) {
    const Eigen::Vector3d a = office.cameraToWorld(i).translation(), b = hall.cameraToWorld(i).translation();
    EXPECT_GT(b.head<2>().norm(), 1.5 * a.head<2>().norm()) << "frame " << i;
    EXPECT_NEAR(b.z(), a.z(), 1e-12);
  }
  EXPECT_LT((hall.cameraToWorld(180).translation() - hall.cameraToWorld(0).translation()).norm(), 0.1);
  for (const double bad : {0.5, 5.0, std::nan("")}) {
    options.room_scale = bad;
    EXPECT_THROW(SyntheticRgbdSequence{options}, std::invalid_argument) << bad;
  }
}

}  // namespace
}  // namespace weighted_icp::simulation
