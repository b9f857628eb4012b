// Dynamic-point filters: points moved by 10 cm are flagged, static ones with
// realistic noise rarely are.

#include <random>

#include <gtest/gtest.h>

#include "test_geometry_scene.h"
#include "weighted_icp/frontend/geometry/dynamic_point_filter.h"

namespace {

using namespace weighted_icp;
using namespace weighted_icp::frontend;
using weighted_icp::testing::gaussianPixel;
using weighted_icp::testing::makePose;
using weighted_icp::testing::perturbPose;
using weighted_icp::testing::pointsInView;
using weighted_icp::testing::projectWorld;
using weighted_icp::testing::syntheticCamera;

TEST(DynamicByDisplacement, FlagsMovedPointsOnAWallAtTwoMetres) {
  const auto camera = syntheticCamera();
  const DepthNoiseModel noise;
  std::mt19937 rng(31);
  const Eigen::Isometry3d truth_wc = makePose({3, -5, 2}, {0.5, 0.1, -0.2});
  const auto points_world = pointsInView(camera, truth_wc, 2000, 2.0, 2.0, rng);  // a fronto-parallel wall
  // The prediction is a little off, as a motion model's is.
  const Eigen::Isometry3d predicted_wc = perturbPose(truth_wc, 0.005, 0.1, rng);

  std::normal_distribution<double> gauss(0.0, 1.0);
  std::vector<Eigen::Vector3d> measured;
  std::vector<bool> moved;
  for (std::size_t i = 0; i < points_world.size(); ++i) {
    Eigen::Vector3d point = points_world[i];
    moved.push_back(i % 10 == 0);
    if (moved.back()) point += 0.10 * Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized();
    // Measured as the sensor would: a noisy pixel and a noisy depth.
    const Eigen::Vector3d in_camera = truth_wc.inverse() * point;
    const Eigen::Vector2d pixel = camera.project(in_camera) + gaussianPixel(noise.pixel_sigma, rng);
    const double depth = in_camera.z() + noise.sigmaDepth(in_camera.z()) * gauss(rng);
    measured.push_back(camera.backProject(pixel.x(), pixel.y(), depth));
  }

  const std::vector<bool> flags = flagDynamicByDisplacement(points_world, measured, predicted_wc, noise);
  ASSERT_EQ(flags.size(), points_world.size());
  int detected = 0, moved_count = 0, false_positives = 0, static_count = 0;
  for (std::size_t i = 0; i < flags.size(); ++i) {
    if (moved[i]) {
      ++moved_count;
      detected += flags[i] ? 1 : 0;
    } else {
      ++static_count;
      false_positives += flags[i] ? 1 : 0;
    }
  }
  const double false_positive_rate = static_cast<double>(false_positives) / static_count;
  std::cout << "displacement filter, wall at 2 m: " << detected << "/" << moved_count << " moved points flagged, "
            << false_positives << "/" << static_count << " static flagged (" << 100 * false_positive_rate << " %)\n";
  EXPECT_EQ(detected, moved_count);
  EXPECT_LT(false_positive_rate, 0.01);
}

TEST(DynamicByDisplacement, DoesNotFlagWhatItCannotMeasure) {
  const std::vector<Eigen::Vector3d> world{{0, 0, 2}, {0, 0, 2}, {std::nan(""), 0, 2}};
  const std::vector<Eigen::Vector3d> measured{{0, 0, 0}, {0, 0, std::nan("")}, {0, 0, 2}};
  const std::vector<bool> flags =
      flagDynamicByDisplacement(world, measured, Eigen::Isometry3d::Identity(), DepthNoiseModel{});
  EXPECT_EQ(flags, std::vector<bool>(3, false));  // zero depth, NaN depth, NaN map point
  EXPECT_THROW(flagDynamicByDisplacement(world, {}, Eigen::Isometry3d::Identity(), DepthNoiseModel{}),
               std::invalid_argument);
}

TEST(DynamicByEpipolarDistance, FlagsPointsMovedAcrossTheirEpipolarPlane) {
  const auto camera = syntheticCamera();
  std::mt19937 rng(32);
  const Eigen::Isometry3d pose_2_in_1 = makePose({1, -2, 0.5}, {0.10, 0.0, 0.01});
  const auto points = pointsInView(camera, Eigen::Isometry3d::Identity(), 3000, 2.0, 4.0, rng);
  constexpr double kPixelSigma = 0.5;  // sub-pixel corners

  std::vector<Eigen::Vector2d> pixels1, pixels2;
  std::vector<bool> moved;
  for (const auto& point : points) {
    const bool moves = pixels1.size() % 10 == 0;
    // Across the epipolar plane (baseline and point), the direction this test can see.
    const Eigen::Vector3d across = pose_2_in_1.translation().cross(point).normalized();
    const Eigen::Vector3d seen_second = moves ? Eigen::Vector3d(point + 0.10 * across) : point;
    const Eigen::Vector2d pixel2 = projectWorld(camera, pose_2_in_1, seen_second);
    if (!camera.inImage(pixel2)) continue;
    moved.push_back(moves);
    pixels1.push_back(camera.project(point) + gaussianPixel(kPixelSigma, rng));
    pixels2.push_back(pixel2 + gaussianPixel(kPixelSigma, rng));
  }

  const std::vector<bool> flags = flagDynamicByEpipolarDistance(pixels1, pixels2, pose_2_in_1, camera);
  int detected = 0, moved_count = 0, false_positives = 0, static_count = 0;
  for (std::size_t i = 0; i < flags.size(); ++i) {
    if (moved[i]) {
      ++moved_count;
      detected += flags[i] ? 1 : 0;
    } else {
      ++static_count;
      false_positives += flags[i] ? 1 : 0;
    }
  }
  const double false_positive_rate = static_cast<double>(false_positives) / static_count;
  std::cout << "epipolar filter, 10 cm baseline, 0.5 px: " << detected << "/" << moved_count
            << " moved points flagged, " << false_positives << "/" << static_count << " static flagged ("
            << 100 * false_positive_rate << " %)\n";
  EXPECT_EQ(detected, moved_count);
  EXPECT_LT(false_positive_rate, 0.01);
}

TEST(DynamicByEpipolarDistance, ExactMatchesHaveZeroDistance) {
  const auto camera = syntheticCamera();
  std::mt19937 rng(33);
  const Eigen::Isometry3d pose_2_in_1 = makePose({0, 5, 0}, {-0.2, 0.05, 0.1});
  const auto points = pointsInView(camera, Eigen::Isometry3d::Identity(), 50, 1.0, 6.0, rng);
  std::vector<Eigen::Vector2d> pixels1, pixels2;
  for (const auto& point : points) {
    pixels1.push_back(camera.project(point));
    pixels2.push_back(projectWorld(camera, pose_2_in_1, point));
  }
  for (const double d : symmetricEpipolarDistances(pixels1, pixels2, pose_2_in_1, camera)) EXPECT_LT(d, 1e-9);
  // No translation, no epipolar geometry: nothing is flagged.
  const std::vector<bool> flags =
      flagDynamicByEpipolarDistance(pixels1, pixels2, makePose({0, 5, 0}, Eigen::Vector3d::Zero()), camera);
  EXPECT_EQ(flags, std::vector<bool>(flags.size(), false));
  EXPECT_THROW(symmetricEpipolarDistances(pixels1, {}, pose_2_in_1, camera), std::invalid_argument);
}

}  // namespace
