// checkFreeSpace on hand-made maps: a keyframe that measured a wall 2 m ahead; landmarks on the wall are
// supported, landmarks in front of it lie in space the keyframe saw through, landmarks behind it are hidden and
// landmarks outside the image or in cells without a measured depth are not judged; each landmark decides by the
// majority of its sightings; the transform between the maps is applied.

#include <gtest/gtest.h>

#include "weighted_icp/mapping/free_space_check.h"

namespace weighted_icp::mapping {
namespace {

PinholeCamera camera() {
  PinholeCamera c;
  c.fx = c.fy = 500.0;
  c.cx = 319.5;
  c.cy = 239.5;
  return c;
}

/// A keyframe at `pose` whose features, every 8 px over the left half of the image, measured depth `depth`.
frontend::Keyframe wallKeyframe(frontend::KeyframeId id, const Eigen::Isometry3d& pose, double depth) {
  frontend::Keyframe keyframe;
  keyframe.id = id;
  keyframe.pose_wc = pose;
  for (int v = 4; v < 480; v += 8)
    for (int u = 4; u < 320; u += 8) {
      keyframe.pixels.emplace_back(u, v);
      keyframe.depths.push_back(depth);
    }
  return keyframe;
}

/// A map of one landmark per position.
KeyframeSnapshot landmarksAt(const std::vector<Eigen::Vector3d>& positions) {
  KeyframeSnapshot snapshot;
  frontend::MapPointId id = 0;
  for (const Eigen::Vector3d& p : positions) {
    frontend::MapPoint point;
    point.id = id;
    point.position = p;
    snapshot.points[id++] = point;
  }
  return snapshot;
}

/// The camera point at pixel (u, v) and depth z, in the world of a keyframe at the identity.
Eigen::Vector3d at(double u, double v, double z) { return camera().backProject(u, v, z); }

TEST(FreeSpaceCheck, LandmarksOnTheWallAreSupportedInFrontViolateBehindAreHidden) {
  KeyframeSnapshot observer;
  observer.keyframes[0] = wallKeyframe(0, Eigen::Isometry3d::Identity(), 2.0);
  const KeyframeSnapshot other = landmarksAt({
      at(100, 100, 2.0),                // on the wall
      at(200, 300, 2.05),               // on the wall, within the margin
      at(100, 200, 1.0),                // 1 m in front of the wall: in free space
      at(150, 50, 1.5),                 // 0.5 m in front: beyond the margin (0.1 + 0.05 * 1.5 = 0.175 m)
      at(120, 120, 3.5),                // behind the wall: hidden, not judged
      at(500, 240, 1.0),                // right half: no depth measured there, not judged
      Eigen::Vector3d(0.0, 0.0, -1.0),  // behind the camera
      at(100, 100, 0.1),                // nearer than any measured depth can be
  });
  const FreeSpaceCheck check = checkFreeSpace(observer, camera(), other, Eigen::Isometry3d::Identity());
  EXPECT_EQ(check.supported_sightings, 2u);
  EXPECT_EQ(check.violating_sightings, 2u);
  EXPECT_EQ(check.landmarks_judged, 4u);
  EXPECT_EQ(check.landmarks_violating, 2u);
  EXPECT_DOUBLE_EQ(check.violationRatio(), 0.5);
}

TEST(FreeSpaceCheck, ALandmarkDecidesByTheMajorityOfItsSightings) {
  // Three keyframes at the identity: two measured the wall at 2 m, one at 1 m (something stood in front then).
  KeyframeSnapshot observer;
  observer.keyframes[0] = wallKeyframe(0, Eigen::Isometry3d::Identity(), 2.0);
  observer.keyframes[1] = wallKeyframe(1, Eigen::Isometry3d::Identity(), 2.0);
  observer.keyframes[2] = wallKeyframe(2, Eigen::Isometry3d::Identity(), 1.0);
  // At 1 m: in the free space of two keyframes, on the surface of one -> violating.
  // At 2 m: on the surface of two, hidden from one -> supported.
  const KeyframeSnapshot other = landmarksAt({at(100, 100, 1.0), at(100, 100, 2.0)});
  const FreeSpaceCheck check = checkFreeSpace(observer, camera(), other, Eigen::Isometry3d::Identity());
  EXPECT_EQ(check.violating_sightings, 2u);
  EXPECT_EQ(check.supported_sightings, 3u);
  EXPECT_EQ(check.landmarks_judged, 2u);
  EXPECT_EQ(check.landmarks_violating, 1u);
}

TEST(FreeSpaceCheck, TheTransformBetweenTheMapsIsApplied) {
  KeyframeSnapshot observer;
  observer.keyframes[0] = wallKeyframe(0, Eigen::Isometry3d::Identity(), 2.0);
  // The other map's world is 1 m behind the observer's along z: its landmark at z = 1 is on the wall.
  const KeyframeSnapshot other = landmarksAt({at(100, 100, 1.0)});
  const Eigen::Isometry3d other_in_observer(Eigen::Translation3d(0.0, 0.0, 1.0));
  FreeSpaceCheck check = checkFreeSpace(observer, camera(), other, other_in_observer);
  EXPECT_EQ(check.landmarks_violating, 0u);
  EXPECT_EQ(check.supported_sightings, 1u);
  check = checkFreeSpace(observer, camera(), other, Eigen::Isometry3d::Identity());
  EXPECT_EQ(check.landmarks_violating, 1u);
  // A keyframe moved 1 m forward sees a landmark 2 m ahead of the origin at 1 m: its own pose is applied too.
  KeyframeSnapshot moved;
  moved.keyframes[0] = wallKeyframe(0, Eigen::Isometry3d(Eigen::Translation3d(0.0, 0.0, 1.0)), 1.0);
  check = checkFreeSpace(moved, camera(), landmarksAt({at(100, 100, 1.0) + Eigen::Vector3d(0.0, 0.0, 1.0)}),
                         Eigen::Isometry3d::Identity());
  EXPECT_EQ(check.supported_sightings, 1u);
  EXPECT_EQ(check.landmarks_violating, 0u);
}

TEST(FreeSpaceCheck, NothingToJudgeIsNoViolation) {
  KeyframeSnapshot observer;
  frontend::Keyframe blind;  // no feature with depth
  blind.pixels.emplace_back(10.0, 10.0);
  blind.depths.push_back(0.0);
  observer.keyframes[0] = blind;
  const FreeSpaceCheck check =
      checkFreeSpace(observer, camera(), landmarksAt({at(10, 10, 1.0)}), Eigen::Isometry3d::Identity());
  EXPECT_EQ(check.landmarks_judged, 0u);
  EXPECT_DOUBLE_EQ(check.violationRatio(), 0.0);
  FreeSpaceCheck sum = check;
  sum += FreeSpaceCheck{1, 3, 2, 1};
  EXPECT_EQ(sum.landmarks_judged, 2u);
  EXPECT_DOUBLE_EQ(sum.violationRatio(), 0.5);
}

}  // namespace
}  // namespace weighted_icp::mapping
