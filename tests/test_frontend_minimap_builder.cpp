// The MiniMapBuilder and the conversion it builds on (toLandmarkMap,
// toWeightedLandmarkCloud), on a hand-made map of two segments: what becomes
// a frame, a landmark and an observation, and how keyframes group into
// mini-maps.

#include <set>
#include <vector>

#include <gtest/gtest.h>

#include "landmark_map_expectations.h"
#include "weighted_icp/frontend/slam/landmark_conversion.h"
#include "weighted_icp/frontend/slam/map.h"
#include "weighted_icp/frontend/slam/minimap_builder.h"

namespace {

using namespace weighted_icp;
using frontend::KeyframeId;

/// Keyframes 0-6 in segment 0 and 7-9 in segment 1, each at x = its id; point
/// i (i = 0..9) is seen by keyframe i and, within its segment, by keyframe
/// i + 1; each point has its own covariance and pixels that name the keyframe.
/// Point ids are 0-9 in that order.
void fillTwoSegments(frontend::Map& map) {
  constexpr KeyframeId kKeyframes = 10, kFirstOfSegment1 = 7;
  for (KeyframeId k = 0; k < kKeyframes; ++k) {
    frontend::Keyframe keyframe;
    keyframe.pose_wc =
        Eigen::Translation3d(static_cast<double>(k), 0.0, 0.0) * Eigen::AngleAxisd(0.1 * k, Eigen::Vector3d::UnitZ());
    keyframe.segment = k < kFirstOfSegment1 ? 0 : 1;
    map.addKeyframe(keyframe);
  }
  for (KeyframeId k = 0; k < kKeyframes; ++k) {
    frontend::MapPoint point;
    point.position = Eigen::Vector3d(static_cast<double>(k), 1.0, 2.0);
    point.covariance = Eigen::Matrix3d::Identity() * (0.001 * (k + 1));
    point.covariance(0, 1) = point.covariance(1, 0) = 0.0001 * k;
    point.observations.push_back({k, Eigen::Vector2d(100.0 + k, 200.0 + k), 2.0});
    const bool next_in_segment = k + 1 < kKeyframes && k + 1 != kFirstOfSegment1;
    if (next_in_segment) point.observations.push_back({k + 1, Eigen::Vector2d(110.0 + k, 210.0 + k), 0.0});
    map.addMapPoint(point);
  }
}

std::set<FrameId> framesOf(const LandmarkMap& map) {
  std::set<FrameId> frames;
  for (const auto& [id, pose] : map.frames) frames.insert(id);
  return frames;
}

TEST(LandmarkConversion, KeyframesBecomeFramesAndPointsLandmarksWithEverything) {
  frontend::Map map;
  fillTwoSegments(map);
  const LandmarkMap converted = frontend::toLandmarkMap(map);
  const auto keyframes = map.keyframes();
  ASSERT_EQ(converted.frames.size(), keyframes.size());
  for (const frontend::Keyframe& keyframe : keyframes) {
    ASSERT_EQ(converted.frames.count(keyframe.id), 1u);
    EXPECT_EQ(converted.frames.at(keyframe.id).matrix(), keyframe.pose_wc.matrix());
  }
  const auto points = map.mapPoints();
  ASSERT_EQ(converted.landmarks.size(), points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Landmark& landmark = converted.landmarks[i];
    EXPECT_EQ(landmark.id, points[i].id);
    EXPECT_EQ(landmark.position, points[i].position);
    EXPECT_EQ(landmark.covariance, points[i].covariance);
    ASSERT_EQ(landmark.observations.size(), points[i].observations.size());
    for (std::size_t k = 0; k < landmark.observations.size(); ++k) {
      EXPECT_EQ(landmark.observations[k].frame_id, points[i].observations[k].keyframe);
      EXPECT_EQ(landmark.observations[k].u, points[i].observations[k].pixel.x());
      EXPECT_EQ(landmark.observations[k].v, points[i].observations[k].pixel.y());
    }
  }
  // The observations name frames the map has: metrics are defined for every landmark.
  for (const Landmark& landmark : converted.landmarks) EXPECT_NO_THROW(converted.metrics(landmark));
  EXPECT_TRUE(frontend::toLandmarkMap(frontend::Map()).landmarks.empty());
}

TEST(LandmarkConversion, SessionMapsAreThinCallers) {
  frontend::Map map;
  fillTwoSegments(map);
  const LandmarkMap converted = frontend::toLandmarkMap(map);
  const LandmarkMap session = frontend::MiniMapBuilder::sessionMap(map);
  EXPECT_EQ(framesOf(session), framesOf(converted));
  weighted_icp::testing::expectSameLandmarks(converted, session);
}

TEST(LandmarkConversion, WeightedCloudHasOnePointPerMapPointWithItsWeight) {
  frontend::Map map;
  fillTwoSegments(map);
  const LandmarkCloud::Ptr cloud = frontend::toWeightedLandmarkCloud(map, ObservationCountWeight{});
  const auto points = map.mapPoints();
  ASSERT_EQ(cloud->size(), points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const LandmarkPoint& p = (*cloud)[i];
    EXPECT_FLOAT_EQ(p.x, static_cast<float>(points[i].position.x()));
    EXPECT_FLOAT_EQ(p.y, static_cast<float>(points[i].position.y()));
    EXPECT_FLOAT_EQ(p.z, static_cast<float>(points[i].position.z()));
    EXPECT_EQ(p.num_observations, points[i].observations.size());
    EXPECT_EQ(p.weight, static_cast<double>(points[i].observations.size()));
    EXPECT_FLOAT_EQ(p.covariance_norm, static_cast<float>(points[i].covariance.norm()));
  }
}

TEST(MiniMapBuilder, GroupsNKeyframesAndNeverCrossesASegment) {
  frontend::Map map;
  fillTwoSegments(map);
  const std::vector<LandmarkMap> minimaps = frontend::MiniMapBuilder(3).build(map);
  // Segment 0 (0-6) in threes, the rest of it alone; segment 1 (7-9) on its own.
  ASSERT_EQ(minimaps.size(), 4u);
  EXPECT_EQ(framesOf(minimaps[0]), (std::set<FrameId>{0, 1, 2}));
  EXPECT_EQ(framesOf(minimaps[1]), (std::set<FrameId>{3, 4, 5}));
  EXPECT_EQ(framesOf(minimaps[2]), (std::set<FrameId>{6}));
  EXPECT_EQ(framesOf(minimaps[3]), (std::set<FrameId>{7, 8, 9}));
  EXPECT_EQ(frontend::MiniMapBuilder(100).build(map).size(), 2u);  // one per segment
  EXPECT_EQ(frontend::MiniMapBuilder(1).build(map).size(), 10u);
  EXPECT_TRUE(frontend::MiniMapBuilder(3).build(frontend::Map()).empty());
}

TEST(MiniMapBuilder, EachMiniMapKeepsOnlyItsKeyframesObservations) {
  frontend::Map map;
  fillTwoSegments(map);
  const LandmarkMap session = frontend::toLandmarkMap(map);
  for (const LandmarkMap& minimap : frontend::MiniMapBuilder(3).build(map)) {
    const std::set<FrameId> frames = framesOf(minimap);
    for (const Landmark& landmark : minimap.landmarks) {
      ASSERT_FALSE(landmark.observations.empty());
      for (const Observation& observation : landmark.observations) EXPECT_EQ(frames.count(observation.frame_id), 1u);
      // Position and covariance as the session estimated them (point ids are indices here).
      const Landmark& whole = session.landmarks.at(landmark.id);
      EXPECT_EQ(landmark.position, whole.position);
      EXPECT_EQ(landmark.covariance, whole.covariance);
    }
  }
  // Point 2 is seen by keyframes 2 and 3: in both of the first two mini-maps, one observation in each.
  const auto minimaps = frontend::MiniMapBuilder(3).build(map);
  for (const std::size_t m : {0u, 1u}) {
    std::size_t found = 0;
    for (const Landmark& landmark : minimaps[m].landmarks)
      if (landmark.id == 2) {
        ++found;
        EXPECT_EQ(landmark.observations.size(), 1u);
      }
    EXPECT_EQ(found, 1u) << "mini-map " << m;
  }
}

TEST(MiniMapBuilder, RefusesZeroKeyframesPerMiniMap) {
  EXPECT_THROW(frontend::MiniMapBuilder(0), std::invalid_argument);
}

}  // namespace
