// Odometry information from tracking: a keyframe held by fewer landmarks is less certain, and a pose graph whose
// odometry edges carry that information puts a loop's correction on the weak edge instead of spreading it.
#include <cmath>
#include <iterator>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>

#include "mapping_fixtures.h"
#include "pose_graph_fixtures.h"
#include "weighted_icp/mapping/pose_graph.h"
#include "weighted_icp/mapping/tracking_information.h"

namespace weighted_icp::testing {
namespace {

using mapping::Covariance6d;

TEST(TrackingInformation, FewerLandmarksGiveALargerCovarianceAndUnknownKeyframesNone) {
  const SyntheticKeyframes data = syntheticKeyframes(12, false, 180.0, {0, 6});
  const auto full = mapping::keyframePoseCovariance(data.snapshot, 1, data.camera);
  ASSERT_TRUE(full.has_value());
  using Solver = Eigen::SelfAdjointEigenSolver<Covariance6d>;
  EXPECT_GT(Solver(*full).eigenvalues().minCoeff(), 0.0);
  EXPECT_LT((*full - full->transpose()).norm(), 1e-9 * full->norm());

  // The same keyframe seeing a quarter of its landmarks: every standard deviation grows.
  mapping::KeyframeSnapshot thinned = data.snapshot;
  std::vector<frontend::MapPointId>& observed = thinned.keyframes.at(1).observed_points;
  std::vector<frontend::MapPointId> kept;
  for (std::size_t i = 0; i < observed.size(); i += 4) kept.push_back(observed[i]);
  observed = kept;
  const auto weak = mapping::keyframePoseCovariance(thinned, 1, data.camera);
  ASSERT_TRUE(weak.has_value());
  for (int axis = 0; axis < 6; ++axis) EXPECT_GT((*weak)(axis, axis), (*full)(axis, axis)) << "axis " << axis;

  EXPECT_FALSE(mapping::keyframePoseCovariance(data.snapshot, 99, data.camera).has_value());
  observed.resize(3);  // below min_observations
  EXPECT_FALSE(mapping::keyframePoseCovariance(thinned, 1, data.camera).has_value());
}

TEST(TrackingInformation, ALandmarkBothKeyframesSeeCancelsInTheRelativePose) {
  const SyntheticKeyframes data = syntheticKeyframes(12, false, 180.0, {0, 3});
  const mapping::KeyframeSnapshot& map = data.snapshot;
  ASSERT_EQ(map.keyframes.size(), 2u);
  const frontend::KeyframeId a = map.keyframes.begin()->first, b = std::next(map.keyframes.begin())->first;
  std::size_t shared = 0;
  for (const auto& [id, point] : map.points) shared += point.observations.size() >= 2 ? 1 : 0;
  ASSERT_GT(shared, 30u) << "the fixture's keyframes must share landmarks";

  mapping::TrackingInformationOptions bare;
  bare.translation_floor_m = bare.rotation_floor_rad = 0.0;
  bare.covariance_inflation = 1.0;  // relativePoseCovariance is without it
  // The relative covariance against the two keyframes' own covariances propagated to the edge.
  const auto separate = [&](const mapping::KeyframeSnapshot& snapshot) {
    return Covariance6d(
        mapping::trackedOdometryInformation(
            snapshot.keyframes.at(a).pose_wc, *mapping::keyframePoseCovariance(snapshot, a, data.camera),
            snapshot.keyframes.at(b).pose_wc, *mapping::keyframePoseCovariance(snapshot, b, data.camera), bare)
            .inverse());
  };
  const auto joint = mapping::relativePoseCovariance(map, a, b, data.camera);
  ASSERT_TRUE(joint.has_value());
  using Solver = Eigen::SelfAdjointEigenSolver<Covariance6d>;
  EXPECT_GT(Solver(*joint).eigenvalues().minCoeff(), 0.0);
  EXPECT_LT((*joint - joint->transpose()).norm(), 1e-9 * joint->norm());
  // The landmarks' own errors move both keyframes alike: counted once per keyframe, they widen the edge.
  const Covariance6d twice = separate(map);
  EXPECT_LT(joint->diagonal().head<3>().sum(), 0.8 * twice.diagonal().head<3>().sum());
  EXPECT_LT(joint->diagonal().tail<3>().sum(), 0.8 * twice.diagonal().tail<3>().sum());

  // With exactly known landmarks nothing is shared but the pixels, and both ways agree once each keyframe keeps only
  // the landmarks both see: one only it sees was mapped from itself (the fixture has no third keyframe), which holds
  // it in keyframePoseCovariance but not in the relative pose.
  mapping::KeyframeSnapshot exact = map;
  for (auto& [id, point] : exact.points) point.covariance.setZero();
  for (auto& [id, keyframe] : exact.keyframes) {
    std::vector<frontend::MapPointId> both;
    for (const frontend::MapPointId point : keyframe.observed_points)
      if (exact.points.at(point).observations.size() >= 2) both.push_back(point);
    keyframe.observed_points = both;
  }
  const auto joint_exact = mapping::relativePoseCovariance(exact, a, b, data.camera);
  ASSERT_TRUE(joint_exact.has_value());
  const Covariance6d separate_exact = separate(exact);
  for (int axis = 0; axis < 6; ++axis)
    EXPECT_NEAR((*joint_exact)(axis, axis), separate_exact(axis, axis), 0.02 * separate_exact(axis, axis))
        << "axis " << axis;

  // All edges at once: the same covariances, none for the first entry or an unknown keyframe.
  const auto edges = mapping::odometryEdgeCovariances(map, {a, b, 99}, data.camera);
  ASSERT_EQ(edges.size(), 3u);
  EXPECT_FALSE(edges[0].has_value());
  ASSERT_TRUE(edges[1].has_value());
  EXPECT_EQ(*edges[1], *joint);
  EXPECT_FALSE(edges[2].has_value());

  EXPECT_FALSE(mapping::relativePoseCovariance(map, a, 99, data.camera).has_value());
  EXPECT_FALSE(mapping::relativePoseCovariance(map, a, a, data.camera).has_value());
}

TEST(TrackingInformation, KeyframesWithoutALandmarkInCommonHaveNoTrackedRelativePose) {
  // As after a frame the dense odometry posed: the newer keyframe sees only landmarks mapped from itself.
  const SyntheticKeyframes data = syntheticKeyframes(12, false, 180.0, {0, 3});
  mapping::KeyframeSnapshot map = data.snapshot;
  ASSERT_EQ(map.keyframes.size(), 2u);
  const frontend::KeyframeId a = map.keyframes.begin()->first, b = std::next(map.keyframes.begin())->first;
  ASSERT_TRUE(mapping::relativePoseCovariance(map, a, b, data.camera).has_value());

  // Every landmark b sees becomes a copy of it that only b observes: same positions, covariances and pixels.
  frontend::MapPointId next_id = map.points.rbegin()->first + 1;
  std::vector<frontend::MapPointId> copies;
  for (const frontend::MapPointId id : map.keyframes.at(b).observed_points) {
    frontend::MapPoint& original = map.points.at(id);
    frontend::MapPoint copy = original;
    copy.id = next_id;
    copy.observations.clear();
    for (auto it = original.observations.begin(); it != original.observations.end();) {
      if (it->keyframe == b) {
        copy.observations.push_back(*it);
        it = original.observations.erase(it);
      } else {
        ++it;
      }
    }
    map.points.emplace(next_id, copy);
    copies.push_back(next_id++);
  }
  map.keyframes.at(b).observed_points = copies;
  ASSERT_TRUE(mapping::keyframePoseCovariance(map, b, data.camera).has_value()) << "b is still held by its landmarks";
  EXPECT_FALSE(mapping::relativePoseCovariance(map, a, b, data.camera).has_value());
  const auto edges = mapping::odometryEdgeCovariances(map, {a, b}, data.camera);
  ASSERT_EQ(edges.size(), 2u);
  EXPECT_FALSE(edges[1].has_value()) << "the pose graph then takes the odometry noise model for this edge";
}

TEST(TrackingInformation, ALandmarkOnlyOneKeyframeSeesHoldsItOnlyWhenAnOlderKeyframeMeasuredIt) {
  // Edge b -> c of three keyframes. c sees, besides its landmarks, a copy of each that only it observes (same
  // position, covariance and pixel): landmarks mapped from c itself.
  const SyntheticKeyframes data = syntheticKeyframes(12, false, 180.0, {0, 3, 6});
  ASSERT_EQ(data.snapshot.keyframes.size(), 3u);
  auto it = data.snapshot.keyframes.begin();
  const frontend::KeyframeId a = (it++)->first, b = (it++)->first, c = it->first;
  const auto before = mapping::relativePoseCovariance(data.snapshot, b, c, data.camera);
  ASSERT_TRUE(before.has_value());
  const auto withCopies = [&](const std::vector<frontend::KeyframeId>& also_observed_by) {
    mapping::KeyframeSnapshot map = data.snapshot;
    frontend::MapPointId next_id = map.points.rbegin()->first + 1;
    std::vector<frontend::MapPointId>& seen = map.keyframes.at(c).observed_points;
    for (const frontend::MapPointId id : std::vector<frontend::MapPointId>(seen)) {
      frontend::MapPoint copy = map.points.at(id);
      copy.id = next_id;
      copy.observations.clear();
      for (const frontend::MapPointObservation& o : map.points.at(id).observations)
        if (o.keyframe == c) copy.observations.push_back(o);
      for (const frontend::KeyframeId other : also_observed_by)
        copy.observations.push_back({other, Eigen::Vector2d::Zero(), 0.0});
      map.points.emplace(next_id, copy);
      seen.push_back(next_id++);
    }
    return mapping::relativePoseCovariance(map, b, c, data.camera);
  };
  // Mapped from c, or seen since by a newer keyframe only: the edge is as it was.
  for (const auto& observers : {std::vector<frontend::KeyframeId>{}, std::vector<frontend::KeyframeId>{c + 1}}) {
    const auto same = withCopies(observers);
    ASSERT_TRUE(same.has_value());
    EXPECT_LT((*same - *before).norm(), 1e-9 * before->norm()) << observers.size() << " other observers";
  }
  // Measured by the older keyframe a too: they hold c in the map, and the edge tightens.
  const auto held = withCopies({a});
  ASSERT_TRUE(held.has_value());
  EXPECT_LT(held->trace(), 0.9 * before->trace()) << held->trace() << " against " << before->trace();
}

/// A circle of 40 keyframes whose odometry is exact but for one step (`bad`), which is 8 cm and 2 degrees off.
DriftedLoop loopWithOneBadStep(std::size_t bad) {
  DriftedLoop loop = makeDriftedLoop(40, 2.0, 0.0, 0.0);
  for (std::size_t i = 0; i < loop.odometry.size(); ++i) loop.odometry[i] = loop.truth[i].inverse() * loop.truth[i + 1];
  Eigen::Isometry3d error = Eigen::Isometry3d::Identity();
  error.translation() = Eigen::Vector3d(0.08, 0.0, 0.0);
  error.linear() = Eigen::AngleAxisd(2.0 * M_PI / 180, Eigen::Vector3d::UnitY()).toRotationMatrix();
  loop.odometry[bad] = loop.odometry[bad] * error;
  loop.drifted.resize(1);
  for (const Eigen::Isometry3d& step : loop.odometry) loop.drifted.push_back(loop.drifted.back() * step);
  return loop;
}

TEST(TrackingInformation, ThePoseGraphPutsTheLoopCorrectionOnTheWeaklyTrackedEdge) {
  const std::size_t bad = 20;
  const DriftedLoop loop = loopWithOneBadStep(bad);
  // Keyframes 20 and 21 were tracked poorly (few landmarks): their standard deviations are 1000 times the others'.
  Covariance6d good = Covariance6d::Identity() * 1e-8;
  const auto covariance = [&](std::size_t k) { return k == bad || k == bad + 1 ? Covariance6d(good * 1e6) : good; };
  mapping::PoseGraph tracked, uniform = makeOdometryGraph(loop);
  for (std::size_t i = 0; i < loop.drifted.size(); ++i) tracked.addNode(i, loop.drifted[i], i == 0);
  for (std::size_t i = 0; i < loop.odometry.size(); ++i)
    tracked.addEdge(
        {i, i + 1, loop.odometry[i],
         mapping::trackedOdometryInformation(loop.drifted[i], covariance(i), loop.drifted[i + 1], covariance(i + 1)),
         mapping::PoseGraphEdgeKind::Odometry});
  for (mapping::PoseGraph* graph : {&tracked, &uniform}) {
    graph->addEdge(trueLoopEdge(loop, 0, 39));
    const auto summary = graph->optimize();
    ASSERT_TRUE(summary.ok) << summary.message;
    EXPECT_EQ(summary.loops_used, 1u);
  }
  const double drifted = rmsPositionError(loop, loop.drifted);
  const double with_tracking = rmsPositionError(loop, posesOf(tracked));
  const double with_model = rmsPositionError(loop, posesOf(uniform));
  ASSERT_GT(drifted, 0.02) << "the fixture must drift for the test to mean anything";
  // The uniform model spreads the correction round the whole loop; the tracked information puts it on the edge
  // that was wrong, and the chain either side keeps its (exact) shape.
  EXPECT_LT(with_tracking, with_model / 3) << "tracking " << with_tracking << " m, model " << with_model << " m";
  EXPECT_LT(with_tracking, drifted / 5) << "drifted " << drifted << " m";
}

TEST(TrackingInformation, InflationAndFloorsSetTheEdgeStandardDeviations) {
  Eigen::Isometry3d a = Eigen::Isometry3d::Identity(), b = Eigen::Isometry3d::Identity();
  b.translation() = Eigen::Vector3d(0.1, 0.0, 0.0);
  mapping::TrackingInformationOptions options;
  options.covariance_inflation = 4.0;
  options.translation_floor_m = 0.001;
  options.rotation_floor_rad = 0.0;
  const Covariance6d each = Covariance6d::Identity() * 1e-6;  // 1 mm, 1 mrad
  const auto information = mapping::trackedOdometryInformation(a, each, b, each, options);
  // Along the step (x) the rotation of `a` does not move b: variance 4 * (1 + 1) mm^2 + the floor's 1 mm^2.
  EXPECT_NEAR(information.inverse()(0, 0), 9e-6, 1e-10);
  // About any axis: 4 * (1 + 1) mrad^2.
  EXPECT_NEAR(information.inverse()(5, 5), 8e-6, 1e-9);
}

}  // namespace
}  // namespace weighted_icp::testing
