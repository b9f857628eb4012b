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

TEST(FrameClock, RoundsJitterAwayAndCountsDroppedFrames) {
  frontend::FrameClock clock;
  EXPECT_FALSE(clock.period());
  EXPECT_EQ(clock.periodsBetween(0.0, 10.0), 1);  // no period known yet
  // 30 Hz with TUM-like jitter (28-36 ms), one frame dropped after the fifth.
  const std::vector<double> intervals = {0.032, 0.028, 0.036, 0.033, 0.031, 0.064, 0.030, 0.034};
  double t = 100.0;
  clock.tick(t);
  std::vector<int> steps;
  for (const double dt : intervals) {
    clock.tick(t + dt);
    steps.push_back(clock.periodsBetween(t, t + dt));
    t += dt;
  }
  EXPECT_EQ(steps, (std::vector<int>{1, 1, 1, 1, 1, 2, 1, 1}));
  ASSERT_TRUE(clock.period());
  EXPECT_NEAR(*clock.period(), 0.0325, 1e-9);  // the median, not the mean the dropped frame pulls up
  EXPECT_EQ(clock.periodsBetween(t, t + 0.0325 * 3.4), 3);
  EXPECT_EQ(clock.periodsBetween(t, t + 0.001), 1);  // never fewer than one
  EXPECT_EQ(clock.periodsBetween(t, t + 1e9), frontend::FrameClock::kMaxPeriods);
  EXPECT_EQ(clock.periodsBetween(t, t - 1.0), 1);  // not increasing
  EXPECT_EQ(clock.periodsBetween(std::nan(""), t), 1);
  // Timestamps that repeat or go back add nothing.
  clock.tick(t);
  clock.tick(t - 5.0);
  clock.tick(std::nan(""));
  EXPECT_NEAR(*clock.period(), 0.0325, 1e-9);
}

TEST(ConstantVelocity, PredictsPerFramePeriodWithTimestamps) {
  const Eigen::Isometry3d step = makePose({1, 2, -0.5}, {0.02, -0.01, 0.05});
  const Eigen::Isometry3d start = makePose({10, 0, 30}, {1, 2, 3});
  frontend::FrameClock clock;
  for (int k = 0; k < 5; ++k) clock.tick(0.033 * k);
  ConstantVelocityModel model;
  model.update(start, 0.0);
  model.update(start * step, 0.033);
  // One period on: the untimed prediction, exactly.
  EXPECT_TRUE(model.predict(0.066, clock)->isApprox(*model.predict(), 1e-15));
  // A dropped frame: two steps on.
  EXPECT_TRUE(model.predict(0.099, clock)->isApprox(start * step * step * step, 1e-9));
  // The last motion spanned two periods (a dropped frame before it): half of it per period.
  model.reset();
  model.update(start, 0.0);
  model.update(start * step * step, 0.066);
  EXPECT_TRUE(model.predict(0.099, clock)->isApprox(start * step * step * step, 1e-9));
  // Without timestamps every pose is one period on.
  model.reset();
  model.update(start);
  model.update(start * step);
  EXPECT_TRUE(model.predict(5.0, clock)->isApprox(start * step * step, 1e-15));
}

TEST(ScaledMotion, IsTheSameMotionPerUnitOfTime) {
  const Eigen::Isometry3d step = makePose({10.0, 20.0, -5.0}, {0.3, -0.2, 0.1});
  EXPECT_TRUE(frontend::scaledMotion(step, 1.0).isApprox(step, 1e-15));
  EXPECT_TRUE(frontend::scaledMotion(step, 0.0).isApprox(Eigen::Isometry3d::Identity(), 1e-15));
  EXPECT_TRUE(frontend::scaledMotion(step, 3.0).isApprox(step * step * step, 1e-12));  // a screw, not a line
  const Eigen::Isometry3d half = frontend::scaledMotion(step, 0.5);
  EXPECT_TRUE((half * half).isApprox(step, 1e-12));
  const Eigen::Isometry3d slide = makePose({0.0, 0.0, 0.0}, {0.3, -0.2, 0.1});  // no rotation: the small-angle form
  EXPECT_TRUE(frontend::scaledMotion(slide, 2.5).translation().isApprox(2.5 * slide.translation(), 1e-12));
  EXPECT_THROW(frontend::scaledMotion(step, -1.0), std::invalid_argument);
  EXPECT_THROW(frontend::scaledMotion(step, std::nan("")), std::invalid_argument);
}

}  // namespace
