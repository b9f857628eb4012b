// registerDepthToColor: the depth an unregistered sensor delivers (simulated by simulation::unregisteredDepth,
// with fr1's lens distortion) moved back into the colour camera's pixels.
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "weighted_icp/core/camera.h"
#include "weighted_icp/frontend/perception/depth_registration.h"
#include "weighted_icp/simulation/image_degradations.h"

namespace weighted_icp::frontend {
namespace {

/// A box 1 m away in front of a slanted wall (1.2 m at the left edge, 3.1 m at the right), as the colour camera
/// sees it: a pixel shift changes the wall's depth too, not only at the box's edges.
cv::Mat boxBeforeAWall(const PinholeCamera& camera) {
  cv::Mat depth(camera.height, camera.width, CV_32F);
  for (int v = 0; v < camera.height; ++v)
    for (int u = 0; u < camera.width; ++u) depth.at<float>(v, u) = 1.2f + 0.003f * static_cast<float>(u);
  depth(cv::Rect(250, 150, 160, 140)).setTo(1.0f);
  return depth;
}

/// The pixels of a 640x480 boxBeforeAWall image that are judged: away from the image border (what the depth camera
/// does not see) and the box's edges (occlusions).
bool judged(int u, int v) {
  if (u < 60 || u >= 640 - 60 || v < 40 || v >= 480 - 40) return false;
  return !(std::abs(u - 250) < 25 || std::abs(u - 410) < 25 || std::abs(v - 150) < 25 || std::abs(v - 290) < 25);
}

TEST(DepthRegistration, UndoesTheDepthCameraOffsetWithTheColourCamerasDistortion) {
  PinholeCamera camera = tumCamera(1);  // k1 = 0.26: the registration must use the colour camera's distortion
  Eigen::Isometry3d depth_in_color = Eigen::Isometry3d::Identity();
  depth_in_color.linear() = Eigen::AngleAxisd(0.5 * M_PI / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix();
  depth_in_color.translation() = Eigen::Vector3d(0.025, 0.0, 0.0);
  const cv::Mat truth = boxBeforeAWall(camera);
  const cv::Mat raw = simulation::unregisteredDepth(truth, camera, depth_in_color);

  DepthCamera sensor{camera.fx, camera.fy, camera.cx, camera.cy, {0.025, 0.0, 0.0}, {0.0, 0.5 * M_PI / 180.0, 0.0}};
  camera.unregistered_depth = sensor;
  const cv::Mat registered = registerDepthToColor(raw, camera);
  ASSERT_EQ(registered.type(), CV_32F);
  ASSERT_EQ(registered.size(), truth.size());
  std::size_t pixels = 0, right_before = 0, right_after = 0, missing = 0;
  for (int v = 0; v < camera.height; ++v)
    for (int u = 0; u < camera.width; ++u) {
      if (!judged(u, v)) continue;
      ++pixels;
      const float z = truth.at<float>(v, u), got = registered.at<float>(v, u);
      missing += !(got > 0.0f);
      right_after += std::abs(got - z) < 0.01f;
      right_before += std::abs(raw.at<float>(v, u) - z) < 0.01f;
    }
  ASSERT_GT(pixels, 100000u);
  EXPECT_GT(static_cast<double>(right_after) / pixels, 0.99) << missing << " missing";
  EXPECT_LT(static_cast<double>(right_before) / pixels, 0.99) << "the offset moved nothing: the test proves nothing";
}

TEST(DepthRegistration, GivesOpenCvsRegisteredDepths) {
  PinholeCamera camera = tumCamera(1);
  const DepthCamera sensor{540.0, 541.0, 322.0, 236.0, {0.025, 0.002, -0.001}, {0.003, 0.0087, -0.002}};
  camera.unregistered_depth = sensor;
  const cv::Mat raw = boxBeforeAWall(camera);
  const cv::Mat ours = registerDepthToColor(raw, camera);
  const cv::Mat theirs = registerDepthWithOpenCv(raw, camera);
  std::size_t both = 0, agree = 0, only_one = 0;
  for (int v = 0; v < raw.rows; ++v)
    for (int u = 0; u < raw.cols; ++u) {
      const float a = ours.at<float>(v, u), b = theirs.at<float>(v, u);
      const bool has_a = a > 0.0f, has_b = b > 0.0f && std::isfinite(b);
      only_one += has_a != has_b;
      if (!(has_a && has_b)) continue;
      ++both;
      agree += std::abs(a - b) < 0.005f;  // the wall rises 3 mm a pixel: splats a pixel apart differ by that
    }
  ASSERT_GT(both, 250000u);
  EXPECT_GT(static_cast<double>(agree) / both, 0.99);
  EXPECT_LT(static_cast<double>(only_one) / both, 0.01);
}

// A depth camera of another resolution than the colour camera's, 2.5 cm aside (an Azure Kinect's 640x576 depth
// beside 1280x720 colour, ScanNet's 640x480 beside 1296x968): every colour pixel gets the depth it shows, with no
// cracks where a depth pixel spans several colour pixels.
TEST(DepthRegistration, ADepthCameraOfAnotherResolutionCoversTheColourImage) {
  const PinholeCamera colour = tumCamera(1);
  Eigen::Isometry3d depth_in_color = Eigen::Isometry3d::Identity();
  depth_in_color.linear() = Eigen::AngleAxisd(0.5 * M_PI / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix();
  depth_in_color.translation() = Eigen::Vector3d(0.025, 0.0, 0.0);
  const cv::Mat truth = boxBeforeAWall(colour);
  PinholeCamera full = colour;  // the depth camera at the colour camera's resolution
  full.unregistered_depth =
      DepthCamera{colour.fx, colour.fy, colour.cx, colour.cy, {0.025, 0.0, 0.0}, {0.0, 0.5 * M_PI / 180.0, 0.0}};
  const cv::Mat full_raw = simulation::unregisteredDepth(truth, colour, depth_in_color);
  for (const double scale : {0.5, 0.37, 2.0}) {
    const PinholeCamera camera = simulation::depthResizedCamera(full, scale);
    const cv::Mat raw = simulation::depthResizedImage(full_raw, full, scale);
    ASSERT_EQ(raw.size(), camera.depthImageSize());
    ASSERT_EQ(raw.cols, std::lround(colour.width * scale));
    const cv::Mat ours = registerDepthToColor(raw, camera), theirs = registerDepthWithOpenCv(raw, camera);
    ASSERT_EQ(ours.size(), cv::Size(colour.width, colour.height));
    ASSERT_EQ(theirs.size(), cv::Size(colour.width, colour.height));
    // The wall rises 3 mm a colour pixel: a colour pixel shows the nearest depth of a footprint about 1.5 depth
    // pixels wide (+ 4 mm of the resampling), a depth pixel spanning 1 / scale colour pixels.
    const float tolerance = 0.003f * static_cast<float>(std::max(2.0, 1.5 / scale)) + 0.004f;
    std::size_t pixels = 0, right = 0, missing = 0, right_opencv = 0, missing_opencv = 0;
    for (int v = 0; v < colour.height; ++v)
      for (int u = 0; u < colour.width; ++u) {
        if (!judged(u, v)) continue;
        ++pixels;
        const float z = truth.at<float>(v, u), got = ours.at<float>(v, u), opencv = theirs.at<float>(v, u);
        missing += !(got > 0.0f);
        missing_opencv += !(opencv > 0.0f);
        right += std::abs(got - z) < tolerance;
        right_opencv += std::abs(opencv - z) < tolerance;
      }
    ASSERT_GT(pixels, 100000u);
    EXPECT_GT(static_cast<double>(right) / pixels, 0.99) << "scale " << scale << ": " << missing << " missing";
    EXPECT_LT(static_cast<double>(missing) / pixels, 0.001) << "scale " << scale;
    // OpenCV's, given the depth resized to the colour image's size (registerDepth reads it over that size).
    EXPECT_GT(static_cast<double>(right_opencv) / pixels, 0.98) << "scale " << scale;
    EXPECT_LT(static_cast<double>(missing_opencv) / pixels, 0.001) << "scale " << scale;
  }
}

TEST(DepthRegistration, RefusesACameraWithoutADepthCameraAndAnotherImage) {
  PinholeCamera camera = tumCamera(3);
  const cv::Mat depth(camera.height, camera.width, CV_32F, cv::Scalar(1.0f));
  EXPECT_THROW(registerDepthToColor(depth, camera), std::invalid_argument);
  EXPECT_THROW(registerDepthWithOpenCv(depth, camera), std::invalid_argument);
  camera.unregistered_depth = DepthCamera{camera.fx, camera.fy, camera.cx, camera.cy, {0.025, 0.0, 0.0}, {}};
  EXPECT_THROW(registerDepthToColor(depth(cv::Rect(0, 0, 320, 240)).clone(), camera), std::invalid_argument);
  cv::Mat millimetres(camera.height, camera.width, CV_16U, cv::Scalar(1000));
  EXPECT_THROW(registerDepthToColor(millimetres, camera), std::invalid_argument);
  // A depth camera of its own size takes depth of that size only.
  camera.unregistered_depth->width = 320;
  camera.unregistered_depth->height = 240;
  EXPECT_THROW(registerDepthToColor(depth, camera), std::invalid_argument);
  EXPECT_EQ(registerDepthToColor(depth(cv::Rect(0, 0, 320, 240)).clone(), camera).size(), depth.size());
}

}  // namespace
}  // namespace weighted_icp::frontend
