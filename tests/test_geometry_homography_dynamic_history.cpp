// The keyframe-to-frame homography (KD-tree paper, Eq. 8) maps points of a
// plane exactly, plane fits find the planes, and the Eq. 6 distance history
// flags a point that starts moving but not static ones.

#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "test_geometry_scene.h"
#include "weighted_icp/frontend/geometry/dynamic_point_history.h"
#include "weighted_icp/frontend/geometry/keyframe_homography.h"

namespace {

using namespace weighted_icp;
using namespace weighted_icp::frontend;

Eigen::Isometry3d pose(double yaw, const Eigen::Vector3d& t) {
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()).toRotationMatrix();
  p.translation() = t;
  return p;
}

TEST(KeyframeHomography, MapsPointsOfThePlaneLikeTheirProjection) {
  const PinholeCamera cam = weighted_icp::testing::syntheticCamera();
  const Eigen::Isometry3d keyframe = pose(0.1, {0.2, -0.1, 0.0}), frame = pose(0.15, {0.28, -0.05, 0.06});
  Plane wall;  // x + 0.2 y + z - 2 = 0 in the world
  wall.normal = Eigen::Vector3d(1, 0.2, 1).normalized();
  wall.offset = -2.0 / Eigen::Vector3d(1, 0.2, 1).norm();
  const Eigen::Matrix3d h = keyframeToFrameHomography(cam, keyframe, frame, wall);
  for (double a = -0.3; a <= 0.3; a += 0.15)
    for (double b = -0.3; b <= 0.3; b += 0.15) {
      // A point on the wall in front of the keyframe.
      const Eigen::Vector3d direction = keyframe.linear() * Eigen::Vector3d(a, b, 1.0);
      const double s = -(wall.offset + wall.normal.dot(keyframe.translation())) / wall.normal.dot(direction);
      const Eigen::Vector3d point = keyframe.translation() + s * direction;
      const Eigen::Vector2d in_keyframe = cam.project(keyframe.inverse() * point);
      const Eigen::Vector2d in_frame = cam.project(frame.inverse() * point);
      EXPECT_LT((applyHomography(h, in_keyframe) - in_frame).norm(), 1e-6);
    }
}

TEST(KeyframeHomography, FitPlanesFindsTwoPlanesAndLeavesClutter) {
  std::vector<Eigen::Vector3d> points;
  std::mt19937 random(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 200; ++i) points.emplace_back(u(random), u(random), 3.0);        // z = 3
  for (int i = 0; i < 120; ++i) points.emplace_back(1.5, u(random), 3.0 + u(random));  // x = 1.5
  for (int i = 0; i < 30; ++i) points.emplace_back(u(random), u(random), 1.0 + u(random));
  const PlaneSet found = fitPlanes(points);
  ASSERT_GE(found.planes.size(), 2u);
  EXPECT_NEAR(std::abs(found.planes[0].normal.z()), 1.0, 1e-6);
  for (int i = 0; i < 200; ++i) EXPECT_EQ(found.plane_of_point[static_cast<std::size_t>(i)], 0);
  const PlaneSet again = fitPlanes(points);
  EXPECT_EQ(again.plane_of_point, found.plane_of_point);
  PlaneFitOptions bad;
  bad.inlier_m = 0.0;
  EXPECT_THROW(fitPlanes(points, bad), std::invalid_argument);
}

TEST(DynamicPointHistory, FlagsAPointThatStartsMovingButNoStaticOne) {
  const PinholeCamera cam = weighted_icp::testing::syntheticCamera();
  std::vector<Eigen::Vector3d> world;
  for (int i = 0; i < 20; ++i) world.emplace_back(-1.0 + 0.1 * i, 0.3 * std::sin(i), 3.0 + 0.05 * i);
  DynamicPointHistory history;
  std::vector<std::uint64_t> ids;
  for (std::uint64_t i = 0; i < world.size(); ++i) ids.push_back(i);
  for (std::size_t frame = 0; frame < 12; ++frame) {
    const Eigen::Isometry3d camera_pose = pose(0.01 * frame, {0.03 * frame, 0.01 * frame, 0.0});
    // Point 5 moves vertically (across the epipolar lines of this sideways motion) from frame 6 on.
    if (frame >= 6) world[5].y() += 0.04;
    std::vector<Eigen::Vector2d> pixels;
    for (const auto& p : world) pixels.push_back(cam.project(camera_pose.inverse() * p));
    const std::vector<bool> flags = history.update(frame, ids, pixels, camera_pose, cam);
    for (std::size_t i = 0; i < world.size(); ++i)
      EXPECT_EQ(flags[i], frame >= 6 && i == 5) << "frame " << frame << ", point " << i;
  }
  EXPECT_THROW(history.update(12, ids, {}, Eigen::Isometry3d::Identity(), cam), std::invalid_argument);
  EXPECT_THROW(DynamicPointHistory({0, 2.0, 3.0, 5}), std::invalid_argument);
  EXPECT_THROW(parseDynamicDistanceKind("speed"), std::invalid_argument);
}

}  // namespace
