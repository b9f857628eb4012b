// The SLAM Map on its own, with hand-made contents: ids, revisions, the local
// map and window of the current segment, what applyOptimization keeps and
// drops, and concurrent writers and readers.

#include <algorithm>
#include <atomic>
#include <set>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "weighted_icp/frontend/slam/map.h"

namespace {

using namespace weighted_icp::frontend;

Keyframe keyframeAt(double x, std::size_t segment = 0) {
  Keyframe keyframe;
  keyframe.pose_wc.translation() = Eigen::Vector3d(x, 0.0, 0.0);
  keyframe.segment = segment;
  return keyframe;
}

/// A point at `position` observed by `keyframes` (pixel u = keyframe id, so observations are told apart).
MapPoint pointSeenBy(const Eigen::Vector3d& position, const std::vector<KeyframeId>& keyframes) {
  MapPoint point;
  point.position = position;
  point.covariance = 0.01 * Eigen::Matrix3d::Identity();
  point.descriptor = cv::Mat(1, 32, CV_8U, cv::Scalar::all(static_cast<int>(position.x() * 10) & 0xff));
  for (const KeyframeId keyframe : keyframes)
    point.observations.push_back({keyframe, Eigen::Vector2d(static_cast<double>(keyframe), 0.0), 1.0});
  return point;
}

std::set<MapPointId> idsOf(const LocalMap& local) { return {local.ids.begin(), local.ids.end()}; }

TEST(Map, AssignsConsecutiveIdsWhateverTheCallerSet) {
  Map map;
  Keyframe keyframe = keyframeAt(0.0);
  keyframe.id = 42;
  EXPECT_EQ(map.addKeyframe(keyframe), 0u);
  EXPECT_EQ(map.addKeyframe(keyframeAt(1.0)), 1u);
  MapPoint point = pointSeenBy({0, 0, 1}, {0});
  point.id = 7;
  EXPECT_EQ(map.addMapPoint(point), 0u);
  EXPECT_EQ(map.addMapPoint(pointSeenBy({1, 0, 1}, {1})), 1u);
  EXPECT_EQ(map.keyframeCount(), 2u);
  EXPECT_EQ(map.mapPointCount(), 2u);
  EXPECT_EQ(map.keyframes()[0].id, 0u);
  ASSERT_TRUE(map.mapPoint(0));
  EXPECT_EQ(map.mapPoint(0)->id, 0u);
  EXPECT_FALSE(map.mapPoint(2));
  EXPECT_FALSE(map.keyframePose(2));
  EXPECT_EQ(map.keyframePose(1)->translation().x(), 1.0);
}

TEST(Map, RefusesAPointObservedByAnUnknownKeyframe) {
  Map map;
  map.addKeyframe(keyframeAt(0.0));
  EXPECT_THROW(map.addMapPoint(pointSeenBy({0, 0, 1}, {0, 3})), std::invalid_argument);
}

TEST(Map, EveryMutationChangesTheRevisionAndReadsDoNot) {
  Map map;
  std::uint64_t revision = map.revision();
  const auto changed = [&] {
    const std::uint64_t now = map.revision();
    const bool different = now != revision;
    revision = now;
    return different;
  };
  map.addKeyframe(keyframeAt(0.0));
  EXPECT_TRUE(changed());
  map.addKeyframe(keyframeAt(1.0));
  EXPECT_TRUE(changed());
  const MapPointId id = map.addMapPoint(pointSeenBy({0, 0, 1}, {0}));
  EXPECT_TRUE(changed());
  map.addObservation(id, {1, {5.0, 5.0}, 1.0}, {0, 0, 1.1}, Eigen::Matrix3d::Identity(), cv::Mat());
  EXPECT_TRUE(changed());
  map.applyOptimization(map.window(2), {});
  EXPECT_TRUE(changed());

  map.localMap(2);
  map.window(2);
  map.keyframes();
  map.mapPoints();
  map.mapPoint(id);
  EXPECT_FALSE(changed());
  // An observation of a point the backend removed meanwhile is dropped, and nothing changes.
  map.addObservation(99, {1, {5.0, 5.0}, 1.0}, {0, 0, 1}, Eigen::Matrix3d::Identity(), cv::Mat());
  EXPECT_FALSE(changed());
}

TEST(Map, AddObservationReplacesTheEstimateAndRegistersWithTheKeyframe) {
  Map map;
  map.addKeyframe(keyframeAt(0.0));
  map.addKeyframe(keyframeAt(1.0));
  const MapPointId id = map.addMapPoint(pointSeenBy({0, 0, 1}, {0}));
  const cv::Mat descriptor(1, 32, CV_8U, cv::Scalar::all(200));
  map.addObservation(id, {1, {3.0, 4.0}, 2.0}, {0.5, 0.5, 1.5}, 2.0 * Eigen::Matrix3d::Identity(), descriptor);
  const MapPoint point = *map.mapPoint(id);
  ASSERT_EQ(point.observations.size(), 2u);
  EXPECT_EQ(point.observations[1].keyframe, 1u);
  EXPECT_EQ(point.observations[1].pixel, Eigen::Vector2d(3.0, 4.0));
  EXPECT_EQ(point.position, Eigen::Vector3d(0.5, 0.5, 1.5));
  EXPECT_EQ(point.covariance, 2.0 * Eigen::Matrix3d::Identity());
  EXPECT_EQ(cv::norm(point.descriptor, descriptor, cv::NORM_HAMMING), 0.0);
  const auto keyframes = map.keyframes();
  EXPECT_EQ(keyframes[1].observed_points, std::vector<MapPointId>{id});
}

TEST(Map, LocalMapTakesOnlyTheLatestKeyframesOfTheCurrentSegment) {
  Map map;
  map.addKeyframe(keyframeAt(0.0, 0));
  map.addKeyframe(keyframeAt(1.0, 0));
  const MapPointId old_segment = map.addMapPoint(pointSeenBy({0, 0, 1}, {0, 1}));
  map.addKeyframe(keyframeAt(2.0, 1));
  map.addKeyframe(keyframeAt(3.0, 1));
  map.addKeyframe(keyframeAt(4.0, 1));
  const MapPointId seen_by_2 = map.addMapPoint(pointSeenBy({2, 0, 1}, {2}));
  const MapPointId seen_by_3 = map.addMapPoint(pointSeenBy({3, 0, 1}, {3}));
  const MapPointId seen_by_2_and_4 = map.addMapPoint(pointSeenBy({4, 0, 1}, {2, 4}));

  const LocalMap all = map.localMap(10);
  EXPECT_EQ(idsOf(all), (std::set<MapPointId>{seen_by_2, seen_by_3, seen_by_2_and_4}));
  EXPECT_EQ(all.ids.size(), 3u);  // once each, however many keyframes saw it
  EXPECT_EQ(all.revision, map.revision());
  ASSERT_EQ(all.positions.size(), all.ids.size());
  ASSERT_EQ(static_cast<std::size_t>(all.descriptors.rows), all.ids.size());
  for (std::size_t i = 0; i < all.ids.size(); ++i) {
    const MapPoint point = *map.mapPoint(all.ids[i]);
    EXPECT_EQ(all.positions[i], point.position);
    EXPECT_EQ(cv::norm(all.descriptors.row(static_cast<int>(i)), point.descriptor, cv::NORM_HAMMING), 0.0);
  }
  EXPECT_EQ(idsOf(map.localMap(2)), (std::set<MapPointId>{seen_by_3, seen_by_2_and_4}));
  EXPECT_EQ(idsOf(map.localMap(1)), (std::set<MapPointId>{seen_by_2_and_4}));
  EXPECT_EQ(idsOf(map.localMap(10)).count(old_segment), 0u);
  EXPECT_TRUE(Map().localMap(5).ids.empty());
}

TEST(Map, WindowIsTheCurrentSegmentOldestFirst) {
  Map map;
  map.addKeyframe(keyframeAt(0.0, 0));
  map.addKeyframe(keyframeAt(1.0, 1));
  map.addKeyframe(keyframeAt(2.0, 1));
  map.addKeyframe(keyframeAt(3.0, 1));
  map.addMapPoint(pointSeenBy({0, 0, 1}, {0}));
  const MapPointId recent = map.addMapPoint(pointSeenBy({3, 0, 1}, {2, 3}));
  const MapWindow window = map.window(2);
  ASSERT_EQ(window.keyframes.size(), 2u);
  EXPECT_EQ(window.keyframes[0].id, 2u);
  EXPECT_EQ(window.keyframes[1].id, 3u);
  ASSERT_EQ(window.points.size(), 1u);
  EXPECT_EQ(window.points[0].id, recent);
  EXPECT_EQ(map.window(10).keyframes.size(), 3u);  // never back into segment 0
  EXPECT_TRUE(Map().window(3).keyframes.empty());
}

TEST(Map, ApplyOptimizationWritesBackAndDropsRejectedObservationsAndOrphans) {
  Map map;
  map.addKeyframe(keyframeAt(0.0));
  map.addKeyframe(keyframeAt(1.0));
  const MapPointId kept = map.addMapPoint(pointSeenBy({0, 0, 1}, {0, 1}));
  const MapPointId orphaned = map.addMapPoint(pointSeenBy({1, 0, 1}, {1}));
  const MapPointId not_rejected = map.addMapPoint(pointSeenBy({2, 0, 1}, {0}));

  MapWindow optimised = map.window(2);
  optimised.keyframes[1].pose_wc.translation() = Eigen::Vector3d(1.1, 0.2, 0.0);
  for (MapPoint& point : optimised.points) {
    point.position += Eigen::Vector3d(0.0, 0.0, 0.5);
    point.covariance = 0.5 * Eigen::Matrix3d::Identity();
  }
  MapPoint gone;  // a point the map no longer has is ignored
  gone.id = 1000;
  optimised.points.push_back(gone);
  map.applyOptimization(optimised, {{kept, 1}, {orphaned, 1}, {1000, 0}});

  EXPECT_EQ(map.keyframePose(1)->translation(), Eigen::Vector3d(1.1, 0.2, 0.0));
  ASSERT_TRUE(map.mapPoint(kept));
  const MapPoint point = *map.mapPoint(kept);
  EXPECT_EQ(point.position, Eigen::Vector3d(0.0, 0.0, 1.5));
  EXPECT_EQ(point.covariance, 0.5 * Eigen::Matrix3d::Identity());
  ASSERT_EQ(point.observations.size(), 1u);
  EXPECT_EQ(point.observations[0].keyframe, 0u);
  EXPECT_FALSE(map.mapPoint(orphaned));  // its only observation was rejected
  EXPECT_EQ(map.mapPointCount(), 2u);
  EXPECT_EQ(map.mapPoint(not_rejected)->position, Eigen::Vector3d(2.0, 0.0, 1.5));
  // Keyframe 1 no longer lists what it was rejected for.
  EXPECT_TRUE(map.keyframes()[1].observed_points.empty());
  EXPECT_EQ(idsOf(map.localMap(1)), std::set<MapPointId>{});
  EXPECT_EQ(idsOf(map.localMap(2)), (std::set<MapPointId>{kept, not_rejected}));
}

TEST(Map, ConcurrentWritersAndReadersSeeWholeUpdates) {
  Map map;
  constexpr int kKeyframes = 200, kPointsPerKeyframe = 5;
  std::atomic<bool> done{false};
  std::atomic<int> inconsistent{0};
  std::thread reader([&] {
    std::uint64_t last_revision = 0;
    while (!done) {
      const std::uint64_t revision = map.revision();
      if (revision < last_revision) ++inconsistent;
      last_revision = revision;
      const LocalMap local = map.localMap(7);
      if (local.positions.size() != local.ids.size() ||
          static_cast<std::size_t>(local.descriptors.rows) != local.ids.size())
        ++inconsistent;
      for (const MapPoint& point : map.mapPoints())
        // A point is added with one observation and its estimate moves to x = 1000 with its second.
        if (point.observations.empty() || (point.observations.size() == 2) != (point.position.x() == 1000.0))
          ++inconsistent;
    }
  });
  for (int k = 0; k < kKeyframes; ++k) {
    const KeyframeId keyframe = map.addKeyframe(keyframeAt(k));
    for (int i = 0; i < kPointsPerKeyframe; ++i) {
      const MapPointId id = map.addMapPoint(pointSeenBy({static_cast<double>(i), 0, 1}, {keyframe}));
      if (keyframe > 0)
        map.addObservation(id, {keyframe - 1, {1.0, 1.0}, 1.0}, {1000.0, 0, 1}, Eigen::Matrix3d::Identity(),
                           cv::Mat(1, 32, CV_8U, cv::Scalar::all(1)));
    }
  }
  done = true;
  reader.join();
  EXPECT_EQ(inconsistent.load(), 0);
  EXPECT_EQ(map.keyframeCount(), static_cast<std::size_t>(kKeyframes));
  EXPECT_EQ(map.mapPointCount(), static_cast<std::size_t>(kKeyframes * kPointsPerKeyframe));
}

TEST(Map, CopyInBlocksHoldsWhatOneCopyUnderTheLockHolds) {
  Map map;
  for (int k = 0; k < 30; ++k) {
    const KeyframeId keyframe = map.addKeyframe(keyframeAt(k));
    for (int i = 0; i < 7; ++i) map.addMapPoint(pointSeenBy({static_cast<double>(i), 0, 1}, {keyframe}));
  }
  const std::vector<Keyframe> keyframes = map.keyframes();
  const std::vector<MapPoint> points = map.mapPoints();
  // Blocks of one, of a few (not dividing the counts) and of more than the map holds.
  for (const auto& [keyframe_block, point_block] :
       std::vector<std::pair<std::size_t, std::size_t>>{{1, 1}, {4, 16}, {1000, 100000}, {0, 0}}) {
    SCOPED_TRACE(std::to_string(keyframe_block) + " " + std::to_string(point_block));
    const MapCopy copy = map.copyInBlocks(keyframe_block, point_block);
    ASSERT_EQ(copy.keyframes.size(), keyframes.size());
    ASSERT_EQ(copy.points.size(), points.size());
    for (std::size_t i = 0; i < keyframes.size(); ++i) {
      EXPECT_EQ(copy.keyframes[i].id, keyframes[i].id);
      EXPECT_TRUE(copy.keyframes[i].pose_wc.isApprox(keyframes[i].pose_wc));
    }
    for (std::size_t i = 0; i < points.size(); ++i) {
      EXPECT_EQ(copy.points[i].id, points[i].id);
      EXPECT_EQ(copy.points[i].position, points[i].position);
    }
  }
  EXPECT_TRUE(Map().copyInBlocks(1, 1).points.empty());
}

// The loop closer copies the map in blocks while tracking applies pose-graph corrections: a copy must never hold
// some points moved by a correction and others not (each correction here moves everything by 1 m along x).
TEST(Map, CopyInBlocksNeverMixesCorrectedAndUncorrectedPoses) {
  Map map;
  constexpr int kKeyframes = 40, kPointsPerKeyframe = 25;
  for (int k = 0; k < kKeyframes; ++k) {
    const KeyframeId keyframe = map.addKeyframe(keyframeAt(0.0));
    for (int i = 0; i < kPointsPerKeyframe; ++i) map.addMapPoint(pointSeenBy({0.0, 0, 1}, {keyframe}));
  }
  std::atomic<bool> done{false};
  std::atomic<int> mixed{0}, copies{0};
  std::thread reader([&] {
    while (!done) {
      const MapCopy copy = map.copyInBlocks(1, 1);  // as many lock releases as possible
      ++copies;
      if (copy.keyframes.empty()) continue;
      const double x = copy.keyframes.front().pose_wc.translation().x();
      for (const Keyframe& keyframe : copy.keyframes) mixed += keyframe.pose_wc.translation().x() != x;
      for (const MapPoint& point : copy.points) mixed += point.position.x() != x;
    }
  });
  Eigen::Isometry3d shift = Eigen::Isometry3d::Identity();
  shift.translation().x() = 1.0;
  for (int c = 0; c < 300; ++c) {
    PoseGraphCorrection correction;
    correction.base_corrections = map.corrections();
    for (KeyframeId k = 0; k < static_cast<KeyframeId>(kKeyframes); ++k) correction.delta_wc[k] = shift;
    ASSERT_TRUE(map.postCorrection(correction));
    ASSERT_TRUE(map.applyPendingCorrection(0));
  }
  done = true;
  reader.join();
  EXPECT_EQ(mixed.load(), 0);
  EXPECT_GT(copies.load(), 0);
  EXPECT_EQ(map.keyframePose(0)->translation().x(), 300.0);
}

}  // namespace
