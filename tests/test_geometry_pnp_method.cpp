// The front-end paper's iterative PnP (cv::SOLVEPNP_ITERATIVE inside RANSAC) next to
// the default AP3P: both recover a known pose through outliers, repeat exactly, and
// the method names round-trip.

#include <random>
#include <stdexcept>

#include <gtest/gtest.h>

#include "test_geometry_scene.h"
#include "weighted_icp/frontend/geometry/pose_estimation.h"
#include "weighted_icp/registration/rigid_motion.h"

namespace {

using namespace weighted_icp;
using namespace weighted_icp::frontend;
using weighted_icp::testing::gaussianPixel;
using weighted_icp::testing::makePose;
using weighted_icp::testing::pointsInView;
using weighted_icp::testing::projectWorld;
using weighted_icp::testing::syntheticCamera;

const Eigen::Isometry3d kMethodTruthWc = makePose({-4, 8, 2}, {0.1, 0.3, -0.4});

/// 300 matches with 1 px noise, the first 20 % replaced by random pixels.
void makeScene(std::vector<Eigen::Vector3d>& points, std::vector<Eigen::Vector2d>& pixels) {
  const auto camera = syntheticCamera();
  std::mt19937 rng(11);
  points = pointsInView(camera, kMethodTruthWc, 300, 1.0, 5.0, rng);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  for (std::size_t i = 0; i < points.size(); ++i) {
    pixels.push_back(projectWorld(camera, kMethodTruthWc, points[i]) + gaussianPixel(1.0, rng));
    if (i < 60) pixels.back() = {uniform(rng) * camera.width, uniform(rng) * camera.height};
  }
}

class PnpMethods : public ::testing::TestWithParam<PnpMethod> {};

TEST_P(PnpMethods, RecoverAKnownPoseThroughOutliersAndRepeatExactly) {
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector2d> pixels;
  makeScene(points, pixels);
  PnpOptions options;
  options.method = GetParam();
  const PoseEstimate first = estimatePosePnp(points, pixels, syntheticCamera(), std::nullopt, options);
  const PoseEstimate second = estimatePosePnp(points, pixels, syntheticCamera(), std::nullopt, options);
  ASSERT_TRUE(first.ok) << first.failure;
  EXPECT_LT(rotationErrorDeg(first.pose_wc, kMethodTruthWc), 0.1);
  EXPECT_LT(translationError(first.pose_wc, kMethodTruthWc), 0.003);
  EXPECT_GE(first.inliers.size(), 230u);  // 240 clean matches, 1 px noise, 3 px threshold
  EXPECT_FALSE(first.initial_from_guess);
  EXPECT_TRUE(first.pose_wc.matrix() == second.pose_wc.matrix());
  EXPECT_EQ(first.inliers, second.inliers);
}

INSTANTIATE_TEST_SUITE_P(Issue11, PnpMethods, ::testing::Values(PnpMethod::Ap3p, PnpMethod::Iterative),
                         [](const ::testing::TestParamInfo<PnpMethod>& info) { return toString(info.param); });

TEST(PnpMethodNames, RoundTripAndUnknownNamesAreRefused) {
  EXPECT_EQ(parsePnpMethod("ap3p"), PnpMethod::Ap3p);
  EXPECT_EQ(parsePnpMethod("iterative"), PnpMethod::Iterative);
  EXPECT_THROW(parsePnpMethod("epnp"), std::invalid_argument);
}

}  // namespace
