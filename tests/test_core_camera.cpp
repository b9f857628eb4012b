// The camera model: TUM calibrations, matrices, projection, its Jacobian and the image bounds; the skew matrix.
#include <limits>
#include <stdexcept>

#include <gtest/gtest.h>

#include "weighted_icp/core/camera.h"
#include "weighted_icp/core/skew.h"

using namespace weighted_icp;

TEST(Camera, TumPresetsHaveThePublishedCalibration) {
  // The values of the TUM RGB-D benchmark's published calibration table.
  const PinholeCamera fr1 = tumCamera(1);
  EXPECT_DOUBLE_EQ(fr1.fx, 517.306408);
  EXPECT_DOUBLE_EQ(fr1.fy, 516.469215);
  EXPECT_DOUBLE_EQ(fr1.cx, 318.643040);
  EXPECT_DOUBLE_EQ(fr1.cy, 255.313989);
  EXPECT_DOUBLE_EQ(fr1.distortion[0], 0.262383);
  EXPECT_DOUBLE_EQ(fr1.distortion[1], -0.953104);
  EXPECT_DOUBLE_EQ(fr1.distortion[2], -0.005358);
  EXPECT_DOUBLE_EQ(fr1.distortion[3], 0.002628);
  EXPECT_DOUBLE_EQ(fr1.distortion[4], 1.163314);
  EXPECT_TRUE(fr1.hasDistortion());

  const PinholeCamera fr2 = tumCamera(2);
  EXPECT_DOUBLE_EQ(fr2.fx, 520.908620);
  EXPECT_DOUBLE_EQ(fr2.fy, 521.007327);
  EXPECT_DOUBLE_EQ(fr2.cx, 325.141442);
  EXPECT_DOUBLE_EQ(fr2.cy, 249.701764);
  EXPECT_DOUBLE_EQ(fr2.distortion[0], 0.231222);
  EXPECT_DOUBLE_EQ(fr2.distortion[3], -0.000105);
  EXPECT_DOUBLE_EQ(fr2.distortion[4], 0.917205);

  const PinholeCamera fr3 = tumCamera(3);
  EXPECT_DOUBLE_EQ(fr3.fx, 535.4);
  EXPECT_DOUBLE_EQ(fr3.fy, 539.2);
  EXPECT_DOUBLE_EQ(fr3.cx, 320.1);
  EXPECT_DOUBLE_EQ(fr3.cy, 247.6);
  EXPECT_FALSE(fr3.hasDistortion());

  for (const auto& camera : {fr1, fr2, fr3}) {
    EXPECT_EQ(camera.width, 640);
    EXPECT_EQ(camera.height, 480);
    EXPECT_DOUBLE_EQ(camera.depth_factor, 5000.0);
  }
  EXPECT_THROW(tumCamera(4), std::invalid_argument);
  EXPECT_THROW(tumCamera(0), std::invalid_argument);
}

TEST(Camera, MatricesHoldTheIntrinsics) {
  const PinholeCamera camera = tumCamera(1);
  const cv::Matx33d k = camera.cameraMatrix();
  EXPECT_EQ(k(0, 0), camera.fx);
  EXPECT_EQ(k(1, 1), camera.fy);
  EXPECT_EQ(k(0, 2), camera.cx);
  EXPECT_EQ(k(1, 2), camera.cy);
  EXPECT_EQ(k(2, 2), 1.0);
  EXPECT_EQ(k(0, 1), 0.0);
  EXPECT_EQ(k(1, 0), 0.0);
  const cv::Mat d = camera.distortionCoefficients();
  ASSERT_EQ(d.type(), CV_64F);
  ASSERT_EQ(d.rows, 1);
  ASSERT_EQ(d.cols, 5);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(d.at<double>(i), camera.distortion[static_cast<std::size_t>(i)]);
}

TEST(Camera, ProjectAndBackProjectAreInverse) {
  const PinholeCamera camera = tumCamera(1);
  for (const Eigen::Vector3d& point :
       {Eigen::Vector3d(0.3, -0.2, 1.5), Eigen::Vector3d(-1.0, 0.7, 4.0), Eigen::Vector3d(0.0, 0.0, 0.6)}) {
    const Eigen::Vector2d pixel = camera.project(point);
    EXPECT_TRUE(camera.backProject(pixel.x(), pixel.y(), point.z()).isApprox(point, 1e-12));
  }
  for (const Eigen::Vector3d& pixel_depth : {Eigen::Vector3d(10.0, 20.0, 1.0), Eigen::Vector3d(600.5, 470.25, 2.5)}) {
    const Eigen::Vector3d point = camera.backProject(pixel_depth.x(), pixel_depth.y(), pixel_depth.z());
    EXPECT_DOUBLE_EQ(point.z(), pixel_depth.z());
    EXPECT_TRUE(camera.project(point).isApprox(pixel_depth.head<2>(), 1e-12));
  }
  // The principal point is where the optical axis meets the image.
  EXPECT_TRUE(camera.project(Eigen::Vector3d(0.0, 0.0, 2.0)).isApprox(Eigen::Vector2d(camera.cx, camera.cy)));
}

TEST(Camera, PointsBehindTheCameraAreNotInTheImage) {
  const PinholeCamera camera = tumCamera(3);
  EXPECT_FALSE(camera.inImage(camera.project(Eigen::Vector3d(0.0, 0.0, -1.0))));
  EXPECT_FALSE(camera.inImage(camera.project(Eigen::Vector3d(0.1, 0.1, 0.0))));
}

TEST(Camera, InImageCoversExactlyThePixelCentres) {
  const PinholeCamera camera = tumCamera(3);
  EXPECT_TRUE(camera.inImage({0.0, 0.0}));
  EXPECT_TRUE(camera.inImage({camera.width - 1.0, camera.height - 1.0}));
  EXPECT_FALSE(camera.inImage({-0.01, 10.0}));
  EXPECT_FALSE(camera.inImage({10.0, -0.01}));
  EXPECT_FALSE(camera.inImage({camera.width - 0.99, 10.0}));
  EXPECT_FALSE(camera.inImage({10.0, camera.height - 0.99}));
  EXPECT_FALSE(camera.inImage({std::numeric_limits<double>::quiet_NaN(), 10.0}));
}

TEST(Camera, ProjectionJacobianMatchesFiniteDifferences) {
  const PinholeCamera camera = tumCamera(3);
  for (const Eigen::Vector3d& point : {Eigen::Vector3d(0.3, -0.2, 1.5), Eigen::Vector3d(-1.0, 0.7, 0.6)}) {
    const Eigen::Matrix<double, 2, 3> jacobian = camera.projectionJacobian(point);
    for (int axis = 0; axis < 3; ++axis) {
      const Eigen::Vector3d step = 1e-6 * Eigen::Vector3d::Unit(axis);
      const Eigen::Vector2d numeric = (camera.project(point + step) - camera.project(point - step)) / 2e-6;
      EXPECT_NEAR((jacobian.col(axis) - numeric).norm(), 0.0, 1e-4) << "axis " << axis;
    }
  }
}

// A depth camera's image resampled: a pixel centre keeps its ray (the centre of old pixel u is new pixel
// (u + 0.5) s - 0.5), the pose and the image size are untouched.
TEST(Camera, AResampledDepthCameraKeepsEachPixelCentresRay) {
  const DepthCamera depth{580.0, 581.0, 314.0, 236.0, {0.025, 0.0, 0.0}, {0.0, 0.01, 0.0}, 640, 480};
  const DepthCamera half = depth.resampled(0.5, 0.5);
  for (const double u : {0.0, 100.0, 639.0}) {
    const double new_u = (u + 0.5) * 0.5 - 0.5;
    EXPECT_NEAR((new_u - half.cx) / half.fx, (u - depth.cx) / depth.fx, 1e-12);
    EXPECT_NEAR((new_u - half.cy) / half.fy, (u - depth.cy) / depth.fy, 1e-12);
  }
  EXPECT_EQ(half.translation_m, depth.translation_m);
  EXPECT_EQ(half.rotation_rad, depth.rotation_rad);
  EXPECT_EQ(half.width, 640);
  const DepthCamera wider = depth.resampled(2.0, 1.0);
  EXPECT_EQ(wider.fx, 1160.0);
  EXPECT_EQ(wider.fy, 581.0);
  EXPECT_EQ(wider.cx, 628.5);
  EXPECT_EQ(wider.cy, 236.0);
}

TEST(Skew, IsTheCrossProductMatrix) {
  const Eigen::Vector3d v(0.5, -2.0, 3.0), w(-1.0, 0.25, 4.0);
  EXPECT_NEAR((skew(v) * w - v.cross(w)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((skew(v) + skew(v).transpose()).norm(), 0.0, 0.0) << "skew-symmetric";
}
