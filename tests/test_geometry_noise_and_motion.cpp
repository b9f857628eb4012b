// Depth noise model, point covariance (against Monte Carlo), fusion, and the
// constant-velocity motion model.

#include <random>

#include <gtest/gtest.h>

#include "test_geometry_scene.h"
#include "weighted_icp/frontend/geometry/depth_noise_model.h"
#include "weighted_icp/frontend/geometry/motion_model.h"

namespace {

using namespace weighted_icp;
using namespace weighted_icp::frontend;
using weighted_icp::testing::makePose;
using weighted_icp::testing::syntheticCamera;

TEST(DepthNoise, DepthSigmaGrowsWithTheSquareOfDepth) {
  const DepthNoiseModel noise;
  EXPECT_DOUBLE_EQ(noise.sigmaDepth(2.0), 0.0015 * 4.0);
  const auto camera = syntheticCamera();
  // At the principal point the depth variance is sigma_z^2 alone.
  const Eigen::Matrix3d near = pointCovarianceCamera(camera, camera.cx, camera.cy, 1.5, noise);
  const Eigen::Matrix3d far = pointCovarianceCamera(camera, camera.cx, camera.cy, 3.0, noise);
  EXPECT_NEAR(std::sqrt(far(2, 2) / near(2, 2)), 4.0, 1e-12);  // twice the depth, four times sigma_z
  EXPECT_NEAR(std::sqrt(near(2, 2)), noise.sigmaDepth(1.5), 1e-15);
  EXPECT_GT(far(0, 0), near(0, 0));  // lateral: z sigma_u / fx grows too
}

TEST(DepthNoise, PointCovarianceMatchesMonteCarlo) {
  const auto camera = syntheticCamera();
  const DepthNoiseModel noise;
  const double u = 560.0, v = 80.0, z = 3.0;  // off-centre, so depth noise also moves x and y
  const Eigen::Matrix3d predicted = pointCovarianceCamera(camera, u, v, z, noise);

  std::mt19937 rng(21);
  std::normal_distribution<double> pixel(0.0, noise.pixel_sigma), depth(0.0, noise.sigmaDepth(z));
  constexpr int kSamples = 200000;
  std::vector<Eigen::Vector3d> samples;
  samples.reserve(kSamples);
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int i = 0; i < kSamples; ++i) {
    const double du = pixel(rng), dv = pixel(rng), dz = depth(rng);
    samples.push_back(camera.backProject(u + du, v + dv, z + dz));
    mean += samples.back();
  }
  mean /= kSamples;
  Eigen::Matrix3d sampled = Eigen::Matrix3d::Zero();
  for (const auto& s : samples) sampled += (s - mean) * (s - mean).transpose();
  sampled /= kSamples - 1;

  std::cout << "point covariance, first order:\n" << predicted << "\nMonte Carlo:\n" << sampled << "\n";
  EXPECT_LT((predicted - sampled).norm() / sampled.norm(), 0.10);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(predicted(k, k) / sampled(k, k), 1.0, 0.10) << "axis " << k;
}

TEST(DepthNoise, RejectsInvalidDepth) {
  const auto camera = syntheticCamera();
  EXPECT_THROW(pointCovarianceCamera(camera, 10, 10, 0.0, {}), std::invalid_argument);
  EXPECT_THROW(pointCovarianceCamera(camera, 10, 10, std::nan(""), {}), std::invalid_argument);
  EXPECT_THROW(pointCovarianceCamera(PinholeCamera{}, 10, 10, 1.0, {}), std::invalid_argument);
}

TEST(PointFusion, TwoEqualCovariancesHalveIt) {
  Eigen::Matrix3d covariance;
  covariance << 4e-4, 1e-4, 0, 1e-4, 3e-4, 0, 0, 0, 9e-4;
  const FusedPoint fused =
      fusePointEstimates({Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(1.2, 2.0, 2.9)}, {covariance, covariance});
  EXPECT_TRUE(fused.covariance.isApprox(0.5 * covariance, 1e-12));
  EXPECT_TRUE(fused.position.isApprox(Eigen::Vector3d(1.1, 2.0, 2.95), 1e-12));
}

TEST(PointFusion, WeightsByInformation) {
  const Eigen::Matrix3d precise = Eigen::Matrix3d::Identity() * 1e-4, vague = Eigen::Matrix3d::Identity() * 9e-4;
  const FusedPoint fused = fusePointEstimates({Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones()}, {precise, vague});
  EXPECT_TRUE(fused.position.isApprox(Eigen::Vector3d::Constant(0.1), 1e-12));  // weights 9 : 1
  EXPECT_TRUE(fused.covariance.isApprox(Eigen::Matrix3d::Identity() * 9e-5, 1e-12));
}

TEST(PointFusion, RejectsInvalidEstimates) {
  const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
  EXPECT_THROW(fusePointEstimates({}, {}), std::invalid_argument);
  EXPECT_THROW(fusePointEstimates({Eigen::Vector3d::Zero()}, {identity, identity}), std::invalid_argument);
  EXPECT_THROW(fusePointEstimates({Eigen::Vector3d::Zero()}, {Eigen::Matrix3d::Zero()}), std::invalid_argument);
  EXPECT_THROW(fusePointEstimates({Eigen::Vector3d::Constant(std::nan(""))}, {identity}), std::invalid_argument);
}

TEST(ConstantVelocity, PredictsConstantMotionExactly) {
  const Eigen::Isometry3d step = makePose({1, 2, -0.5}, {0.02, -0.01, 0.05});
  Eigen::Isometry3d pose = makePose({10, 0, 30}, {1, 2, 3});
  ConstantVelocityModel model;
  EXPECT_FALSE(model.predict());
  model.update(pose);
  EXPECT_FALSE(model.predict());  // no velocity from a single pose
  for (int k = 0; k < 5; ++k) {
    pose = pose * step;
    model.update(pose);
    const auto predicted = model.predict();
    ASSERT_TRUE(predicted);
    EXPECT_TRUE(predicted->isApprox(pose * step, 1e-12));
  }
  model.reset();
  EXPECT_FALSE(model.predict());
  Eigen::Isometry3d broken = pose;
  broken.translation().x() = std::nan("");
  EXPECT_THROW(model.update(broken), std::invalid_argument);
}

}  // namespace
