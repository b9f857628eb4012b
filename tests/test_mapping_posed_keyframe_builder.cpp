// PosedKeyframeBuilder (what wicp_vocabulary trains on): a sensor whose depth camera is not its colour camera, here
// of half its resolution, gives the landmarks the registered depth gives; depth of another size is refused.
#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "weighted_icp/mapping/posed_keyframe_builder.h"
#include "weighted_icp/simulation/image_degradations.h"
#include "weighted_icp/simulation/rgbd_sequence.h"

namespace weighted_icp {
namespace {

TEST(PosedKeyframeBuilder, AHalfResolutionDepthCameraGivesTheLandmarksOfTheRegisteredDepth) {
  simulation::SyntheticRgbdOptions options;
  options.frames = 3;
  const simulation::SyntheticRgbdSequence sequence(options);
  const PinholeCamera registered = options.camera;
  const PinholeCamera half = simulation::depthResizedCamera(registered, 0.5);
  ASSERT_EQ(half.depthImageSize(), cv::Size(registered.width / 2, registered.height / 2));
  mapping::PosedKeyframeBuilder full_builder(registered), half_builder(half);
  for (std::size_t i = 0; i < sequence.size(); ++i) {
    const simulation::SyntheticRgbdFrame frame = sequence.frame(i);
    full_builder.add(frame.rgbd, i, frame.camera_to_world);
    RgbdFrame coarse = frame.rgbd;
    coarse.depth = simulation::depthResizedImage(frame.rgbd.depth, registered, 0.5);
    half_builder.add(coarse, i, frame.camera_to_world);
  }
  const std::vector<frontend::MapPoint> full = full_builder.map().mapPoints(), coarse = half_builder.map().mapPoints();
  ASSERT_GT(full.size(), 200u);
  EXPECT_GT(coarse.size(), 8 * full.size() / 10);
  // Each landmark of the coarse depth has one of the registered depth within 2 cm (the same corner, its depth read a
  // pixel or two aside on the coarser grid).
  std::size_t near = 0;
  for (const frontend::MapPoint& point : coarse) {
    double nearest = std::numeric_limits<double>::infinity();
    for (const frontend::MapPoint& other : full) nearest = std::min(nearest, (other.position - point.position).norm());
    near += nearest < 0.02;
  }
  EXPECT_GT(static_cast<double>(near) / static_cast<double>(coarse.size()), 0.95);

  // Depth of the colour image's size where the camera says 320x240: refused, naming both sizes.
  const simulation::SyntheticRgbdFrame frame = sequence.frame(0);
  try {
    half_builder.add(frame.rgbd, 0, frame.camera_to_world);
    FAIL() << "depth of the wrong size accepted";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("CV_32F depth of 320x240"), std::string::npos) << what;
    EXPECT_NE(what.find("colour of 640x480"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace weighted_icp
