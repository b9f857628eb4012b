// LandmarkMap (mini-maps, transform, filtering, metrics) and the weight
// strategies, on hand-made landmarks whose values are worked out by hand.

#include <map>
#include <string>

#include <gtest/gtest.h>

#include "weighted_icp/registration/landmark_map.h"
#include "weighted_icp/registration/weight_strategies.h"

namespace {

using namespace weighted_icp;

Eigen::Isometry3d at(double x, double y, double z) { return Eigen::Isometry3d(Eigen::Translation3d(x, y, z)); }

/// Frames 10..50 (ids not contiguous). Landmark 1 at the origin is seen from
/// frame 10 at distance 5 and frame 40 at distance 2; landmark 2 only by frame
/// 20; landmark 3 by none; landmark 4 only by frame 50.
LandmarkMap fiveFrames() {
  LandmarkMap map;
  map.frames[10] = at(3, 4, 0);
  map.frames[20] = at(1, 1, 3);
  map.frames[30] = at(-1, 0, 0);
  map.frames[40] = at(0, 0, 2);
  map.frames[50] = at(0, 6, 0);
  map.landmarks = {
      {1, Eigen::Vector3d::Zero(), Eigen::Vector3d(4e-4, 1e-4, 1e-4).asDiagonal(), {{10, 1, 2}, {40, 3, 4}}},
      {2, Eigen::Vector3d(1, 1, 1), Eigen::Matrix3d::Identity() * 1e-3, {{20, 5, 6}}},
      {3, Eigen::Vector3d(2, 0, 0), Eigen::Matrix3d::Identity() * 1e-2, {}},
      {4, Eigen::Vector3d(0, 1, 0), Eigen::Matrix3d::Identity() * 2e-3, {{50, 7, 8}}},
  };
  return map;
}

std::vector<FrameId> frameIds(const LandmarkMap& map) {
  std::vector<FrameId> ids;
  for (const auto& [id, pose] : map.frames) ids.push_back(id);
  return ids;
}

std::vector<LandmarkId> landmarkIds(const LandmarkMap& map) {
  std::vector<LandmarkId> ids;
  for (const auto& landmark : map.landmarks) ids.push_back(landmark.id);
  return ids;
}

std::vector<FrameId> observingFrames(const Landmark& landmark) {
  std::vector<FrameId> ids;
  for (const auto& observation : landmark.observations) ids.push_back(observation.frame_id);
  return ids;
}

TEST(MiniMap, KeepsTheFramesOfItsRange) {
  const LandmarkMap map = fiveFrames();
  EXPECT_EQ(frameIds(map.miniMap(10, 20)), (std::vector<FrameId>{10, 20}));
  EXPECT_EQ(frameIds(map.miniMap(15, 35)), (std::vector<FrameId>{20, 30}));
  EXPECT_EQ(frameIds(map.miniMap(50, 1000)), (std::vector<FrameId>{50}));
  EXPECT_TRUE(map.miniMap(51, 60).frames.empty());
  EXPECT_TRUE(map.miniMap(51, 60).landmarks.empty());
  EXPECT_TRUE(map.miniMap(30, 40).frames.at(30).isApprox(map.frames.at(30)));
}

TEST(MiniMap, LandmarkSeenInTwoRangesGoesToBothWithItsInRangeObservations) {
  const LandmarkMap map = fiveFrames();
  const LandmarkMap first = map.miniMap(10, 20);
  const LandmarkMap second = map.miniMap(30, 50);
  ASSERT_EQ(landmarkIds(first), (std::vector<LandmarkId>{1, 2}));
  ASSERT_EQ(landmarkIds(second), (std::vector<LandmarkId>{1, 4}));  // 3 is seen by no frame
  EXPECT_EQ(observingFrames(first.landmarks[0]), (std::vector<FrameId>{10}));
  EXPECT_EQ(observingFrames(second.landmarks[0]), (std::vector<FrameId>{40}));
  EXPECT_EQ(first.landmarks[0].observations[0].u, 1.0);
  EXPECT_EQ(second.landmarks[0].observations[0].v, 4.0);

  // Mean distance to the cameras that saw it in the mini-map: 5 and 2, not the session's 3.5.
  EXPECT_DOUBLE_EQ(map.meanObservationDistance(map.landmarks[0]), 3.5);
  EXPECT_DOUBLE_EQ(first.meanObservationDistance(first.landmarks[0]), 5.0);
  EXPECT_DOUBLE_EQ(second.meanObservationDistance(second.landmarks[0]), 2.0);

  // Position and covariance are the session's estimate.
  EXPECT_EQ(second.landmarks[0].position, map.landmarks[0].position);
  EXPECT_EQ(second.landmarks[0].covariance, map.landmarks[0].covariance);
}

TEST(MiniMap, SplitIntoConsecutiveFrameCounts) {
  const LandmarkMap map = fiveFrames();
  const std::vector<LandmarkMap> minis = map.splitIntoMiniMaps(2);
  ASSERT_EQ(minis.size(), 3u);
  EXPECT_EQ(frameIds(minis[0]), (std::vector<FrameId>{10, 20}));
  EXPECT_EQ(frameIds(minis[1]), (std::vector<FrameId>{30, 40}));
  EXPECT_EQ(frameIds(minis[2]), (std::vector<FrameId>{50}));  // the last is shorter
  EXPECT_EQ(landmarkIds(minis[0]), (std::vector<LandmarkId>{1, 2}));
  EXPECT_EQ(landmarkIds(minis[1]), (std::vector<LandmarkId>{1}));
  EXPECT_EQ(landmarkIds(minis[2]), (std::vector<LandmarkId>{4}));

  EXPECT_EQ(map.splitIntoMiniMaps(5).size(), 1u);
  EXPECT_EQ(map.splitIntoMiniMaps(6).size(), 1u);
  EXPECT_EQ(map.splitIntoMiniMaps(1).size(), 5u);
  EXPECT_TRUE(LandmarkMap().splitIntoMiniMaps(3).empty());
  EXPECT_THROW(map.splitIntoMiniMaps(0), std::invalid_argument);
}

TEST(LandmarkMapTransform, MovesPosesAndPositionsAndRotatesCovariances) {
  const LandmarkMap map = fiveFrames();
  Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
  motion.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  motion.translation() = Eigen::Vector3d(1.0, -2.0, 0.5);
  const Eigen::Matrix3d rotation = motion.linear();
  LandmarkMap moved = map;
  moved.transform(motion);

  for (const auto& [id, pose] : map.frames) {
    EXPECT_TRUE(moved.frames.at(id).translation().isApprox(rotation * pose.translation() + motion.translation()));
    EXPECT_TRUE(moved.frames.at(id).linear().isApprox(rotation * pose.linear()));
  }
  for (std::size_t i = 0; i < map.landmarks.size(); ++i) {
    const Landmark& before = map.landmarks[i];
    const Landmark& after = moved.landmarks[i];
    EXPECT_LT((after.position - (rotation * before.position + motion.translation())).norm(), 1e-12);
    EXPECT_TRUE(after.covariance.isApprox(rotation * before.covariance * rotation.transpose(), 1e-12));
    EXPECT_NEAR(moved.meanObservationDistance(after), map.meanObservationDistance(before), 1e-12);
  }
  // Landmark 1's covariance is elongated along x: after the motion along R x, with the same variance.
  const Eigen::Vector3d long_axis = rotation * Eigen::Vector3d::UnitX();
  EXPECT_TRUE((moved.landmarks[0].covariance * long_axis).isApprox(4e-4 * long_axis, 1e-12));
}

TEST(LandmarkMapFilter, WithMinObservations) {
  const LandmarkMap map = fiveFrames();
  EXPECT_EQ(landmarkIds(map.withMinObservations(0)), (std::vector<LandmarkId>{1, 2, 3, 4}));
  EXPECT_EQ(landmarkIds(map.withMinObservations(1)), (std::vector<LandmarkId>{1, 2, 4}));
  EXPECT_EQ(landmarkIds(map.withMinObservations(2)), (std::vector<LandmarkId>{1}));
  EXPECT_TRUE(map.withMinObservations(3).landmarks.empty());
  EXPECT_EQ(frameIds(map.withMinObservations(3)), frameIds(map));
}

// Landmarks both maps hold go to one only, by id parity (the first keeps the even ids); the others stay where they are.
TEST(LandmarkMapFilter, DealOutSharedLandmarksLeavesNoLandmarkInBoth) {
  const LandmarkMap map = fiveFrames();  // landmarks 1-4
  LandmarkMap a = map, b = map;
  a.landmarks.erase(a.landmarks.begin() + 3);  // a: 1, 2, 3
  b.landmarks.erase(b.landmarks.begin());      // b: 2, 3, 4
  dealOutSharedLandmarks(a, b);
  EXPECT_EQ(landmarkIds(a), (std::vector<LandmarkId>{1, 2}));
  EXPECT_EQ(landmarkIds(b), (std::vector<LandmarkId>{3, 4}));
  EXPECT_EQ(frameIds(a), frameIds(map));
}

TEST(LandmarkMapFilter, ToFirstCameraFrameMakesTheFirstCameraTheOrigin) {
  LandmarkMap map = fiveFrames();
  map.frames[10].linear() = Eigen::AngleAxisd(0.5, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const LandmarkMap before = map;
  const Eigen::Isometry3d first = map.toFirstCameraFrame();
  EXPECT_TRUE(first.isApprox(before.frames.at(10)));
  EXPECT_LT((map.frames.at(10).matrix() - Eigen::Matrix4d::Identity()).norm(), 1e-12);
  for (std::size_t i = 0; i < map.landmarks.size(); ++i)
    EXPECT_LT((map.landmarks[i].position - first.inverse() * before.landmarks[i].position).norm(), 1e-12) << i;
  EXPECT_THROW(LandmarkMap{}.toFirstCameraFrame(), std::invalid_argument);
}

TEST(LandmarkMapMetrics, MeanObservationDistanceNamesAnUnknownFrame) {
  const LandmarkMap map = fiveFrames();
  const Landmark stray{7, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity(), {{10, 0, 0}, {99, 0, 0}}};
  try {
    map.meanObservationDistance(stray);
    FAIL() << "no error for an unknown frame";
  } catch (const std::out_of_range& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("landmark 7"), std::string::npos) << message;
    EXPECT_NE(message.find("frame 99"), std::string::npos) << message;
  }
}

TEST(LandmarkMapMetrics, OfHandMadeLandmarks) {
  const LandmarkMap map = fiveFrames();
  const LandmarkMetrics seen_twice = map.metrics(map.landmarks[0]);
  EXPECT_EQ(seen_twice.covariance, map.landmarks[0].covariance);
  EXPECT_EQ(seen_twice.num_observations, 2u);
  EXPECT_DOUBLE_EQ(seen_twice.mean_observation_distance, 3.5);
  // Landmark 2 at (1,1,1) seen from (1,1,3).
  EXPECT_DOUBLE_EQ(map.metrics(map.landmarks[1]).mean_observation_distance, 2.0);
  const LandmarkMetrics unseen = map.metrics(map.landmarks[2]);
  EXPECT_EQ(unseen.num_observations, 0u);
  EXPECT_EQ(unseen.mean_observation_distance, 0.0);
}

/// diag(3, 4, 0): Frobenius norm 5, spectral norm 4. Seen 3 times at a mean
/// distance of 1.5.
LandmarkMetrics handMadeMetrics() {
  LandmarkMetrics m;
  m.covariance = Eigen::Vector3d(3, 4, 0).asDiagonal();
  m.num_observations = 3;
  m.mean_observation_distance = 1.5;
  return m;
}

TEST(WeightStrategies, ValuesOnAHandMadeLandmark) {
  const LandmarkMetrics m = handMadeMetrics();
  EXPECT_DOUBLE_EQ(CovarianceWeight{}(m), 1.0 / 6.0);  // 1 / (1 + 5); the spectral norm would give 1/5
  EXPECT_DOUBLE_EQ(ObservationCountWeight{}(m), 3.0);
  EXPECT_DOUBLE_EQ(MeanObservationDistanceWeight{}(m), 1.0 / 2.5);
  EXPECT_DOUBLE_EQ(UniformWeight{}(m), 1.0);
}

TEST(WeightStrategies, CovarianceWeightUsesTheFrobeniusNormOfNonDiagonalCovariances) {
  LandmarkMetrics m;
  // Eigenvalues 4, 0, 1 (spectral norm 4); entries' squares sum to 17.
  m.covariance << 2, 2, 0, 2, 2, 0, 0, 0, 1;
  EXPECT_DOUBLE_EQ(CovarianceWeight{}(m), 1.0 / (1.0 + std::sqrt(17.0)));
}

TEST(WeightStrategies, EachNamedStrategyGivesItsValue) {
  const std::map<std::string, double> expected{
      {"base", 1.0}, {"covariance", 1.0 / 6.0}, {"observations", 3.0}, {"mean-distance", 1.0 / 2.5}};
  const LandmarkMetrics m = handMadeMetrics();
  ASSERT_EQ(allWeightStrategies().size(), expected.size());
  for (const WeightStrategy strategy : allWeightStrategies()) {
    const std::string name = toString(strategy);
    ASSERT_TRUE(expected.count(name)) << "no expected value for strategy " << name;
    EXPECT_EQ(parseWeightStrategy(name), strategy);
    EXPECT_DOUBLE_EQ(weightFunction(strategy)(m), expected.at(name)) << name;
  }
  EXPECT_THROW(parseWeightStrategy("frobenius"), std::invalid_argument);
}

}  // namespace
