// The synthetic sequence's loop options: frames_per_loop brings the camera
// back to its start, repeated_texture changes the images but not the path,
// and both leave the default sequence as it was.

#include <gtest/gtest.h>

#include "weighted_icp/simulation/rgbd_sequence.h"

namespace weighted_icp::simulation {
namespace {

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
  SyntheticRgbdOptions options;
  options.frames = 2;
  options.camera.width = 160;
  options.camera.height = 120;
  options.camera.fx = options.camera.fy = 130.0;
  options.camera.cx = 80.0;
  options.camera.cy = 60.0;
  const SyntheticRgbdFrame plain = SyntheticRgbdSequence(options).frame(1);
  options.repeated_texture = true;
  const SyntheticRgbdFrame aliased = SyntheticRgbdSequence(options).frame(1);
  EXPECT_TRUE(plain.camera_to_world.isApprox(aliased.camera_to_world));
  EXPECT_GT(cv::norm(plain.rgbd.color, aliased.rgbd.color, cv::NORM_L1) / plain.rgbd.color.total(), 5.0);
  // Geometry is the same: depth differs only by its noise, which is a hash of the pixel (so not at all).
  EXPECT_EQ(cv::norm(plain.rgbd.depth, aliased.rgbd.depth, cv::NORM_INF), 0.0);
}

}  // namespace
}  // namespace weighted_icp::simulation
