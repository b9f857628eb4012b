// Alignment from any start (GlobalAlignment, GlobalLandmarkAligner): a yaw of
// 180° and metres of translation on real landmarks, a partial overlap whose
// shared landmarks are dealt out between the maps, and bad input.

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include <pcl/common/io.h>

#include "test_landmark_pairs.h"
#include "test_support.h"
#include "weighted_icp/io/map_format.h"
#include "weighted_icp/registration/global_landmark_alignment.h"
#include "weighted_icp/registration/rigid_motion.h"

namespace {

using namespace weighted_icp;
using weighted_icp::testing::disjointPair;
using weighted_icp::testing::mapAndMiniMap;

/// Aligns `source`, displaced by `d`, onto `target`, checks the result undoes the displacement and returns it.
GlobalLandmarkAlignmentResult expectRecovered(const LandmarkMap& source, const LandmarkMap& target,
                                              const Displacement& d) {
  LandmarkMap moved = source;
  moved.transform(d.toIsometry());
  GlobalLandmarkAligner aligner;
  aligner.setTarget(toLandmarkCloud(target, CovarianceWeight{}));
  const GlobalLandmarkAlignmentResult result = aligner.align(toLandmarkCloud(moved, CovarianceWeight{}));
  const Eigen::Isometry3d truth = d.toIsometry().inverse(), estimate(result.alignment.transformation);
  EXPECT_LT(rotationErrorDeg(estimate, truth), 2.0) << d.toString();
  EXPECT_LT(translationError(estimate, truth), 0.05) << d.toString();
  EXPECT_GT(result.global.inlier_fraction, 0.0);
  EXPECT_FALSE(result.alignment.degenerate);
  return result;
}

TEST(GlobalAlignment, RecoversYaw180OnDisjointHalvesOfTheRealMap) {
  WEIGHTED_ICP_REQUIRE_FILE(weighted_icp::testing::realMapPath());
  const auto [even, odd] =
      io::readLandmarkMap(weighted_icp::testing::realMapPath().string()).withMinObservations(2).alternateHalves();
  expectRecovered(odd, even, Displacement{1.5, -1.0, 0.0, 0.0, 0.0, 180.0});
}

TEST(GlobalAlignment, RecoversAPartialOverlapWithNoSharedLandmark) {
  WEIGHTED_ICP_REQUIRE_FILE(weighted_icp::testing::realMapPath());
  // Frames 0-143 and 96-239: a third of each one's frames shared; landmarks both saw dealt out by id parity.
  const auto [a, b] = disjointPair(io::readLandmarkMap(weighted_icp::testing::realMapPath().string()), 143, 96);
  ASSERT_GT(a.landmarks.size(), 1000u);
  expectRecovered(b, a, Displacement{-2.0, 1.0, 0.0, 0.0, 0.0, 135.0});
}

TEST(GlobalAlignment, ClimbsToTheTruthWhenItsBestVoteEndsBeyondTheFineWindow) {
  WEIGHTED_ICP_REQUIRE_FILE(weighted_icp::testing::realMapPath());
  const LandmarkMap map = io::readLandmarkMap(weighted_icp::testing::realMapPath().string());
  // wicp_global_sweep's disjoint pair at overlap 0.15 (frames 0-129 and 110-239, landmarks both saw dealt out by id
  // parity), the source turned 60 degrees: the truth's coarse hypothesis is not among the best voted, its neighbour
  // 10 degrees off ends where a second search from there reaches the truth.
  const auto [target, source] = disjointPair(map, 129, 110);
  const Displacement d{0.0, 0.0, 0.0, 0.0, 0.0, 60.0};
  expectRecovered(source, target, d);
  // Without the climb the search of 10-degree rotations (the default until 2026-11-29, on which the climb was built;
  // 5-degree rotations find this case either way) ends outside its fine window (6 degrees).
  GlobalAlignmentSettings no_climb;
  no_climb.yaw_hypotheses = 36;
  no_climb.tilted_hypotheses = 3;
  no_climb.climbed_hypotheses = 0;
  GlobalAlignment global(no_climb);
  GlobalAlignment::Cloud source_xyz, target_xyz;
  pcl::copyPointCloud(*toLandmarkCloud(target, CovarianceWeight{}), target_xyz);
  LandmarkMap moved = source;
  moved.transform(d.toIsometry());
  pcl::copyPointCloud(*toLandmarkCloud(moved, CovarianceWeight{}), source_xyz);
  global.setTarget(target_xyz);
  const Eigen::Isometry3d estimate(global.align(source_xyz).transformation);
  EXPECT_GT(rotationErrorDeg(estimate, d.toIsometry().inverse()), 6.0);
}

TEST(GlobalAlignment, FiveDegreeRotationsFindPiecesSharingAFewFrames) {
  WEIGHTED_ICP_REQUIRE_FILE(weighted_icp::testing::realMapPath());
  const LandmarkMap map = io::readLandmarkMap(weighted_icp::testing::realMapPath().string());
  // wicp_global_sweep's pieces sharing 6 of 240 frames (0-122 and 117-239, their shared landmarks kept), as given:
  // the truth's rotation was not among the best voted 10-degree rotations, whose search ended 8.6 degrees off.
  const LandmarkMap target = map.miniMap(0, 122).withMinObservations(2);
  const LandmarkMap source = map.miniMap(117, 239).withMinObservations(2);
  expectRecovered(source, target, Displacement{});
  GlobalAlignmentSettings ten_degrees;
  ten_degrees.yaw_hypotheses = 36;
  ten_degrees.tilted_hypotheses = 3;
  GlobalLandmarkAligner aligner(ten_degrees);
  aligner.setTarget(toLandmarkCloud(target, CovarianceWeight{}));
  const Eigen::Isometry3d estimate(aligner.align(toLandmarkCloud(source, CovarianceWeight{})).alignment.transformation);
  EXPECT_GT(rotationErrorDeg(estimate, Eigen::Isometry3d::Identity()), 2.0);
}

TEST(GlobalAlignment, AlignsAWholeMapOntoOneOfItsMiniMapsByTheSearchTheOtherWay) {
  WEIGHTED_ICP_REQUIRE_FILE(weighted_icp::testing::realMapPath());
  // The whole map (about 1,200 sample voxels) onto ten of its frames (about 75): of the source's 400 vote samples a
  // few lie where the mini-map is, and the search once ended 160-180 degrees off. It now runs the mini-map onto the
  // whole map and inverts the result.
  const auto [whole, mini] = mapAndMiniMap(io::readLandmarkMap(weighted_icp::testing::realMapPath().string()), 60, 69);
  ASSERT_GT(whole.landmarks.size(), 10 * mini.landmarks.size());
  const Displacement d{2.0, -2.0, 0.0, 0.0, 0.0, 90.0};
  const GlobalLandmarkAlignmentResult reversed = expectRecovered(whole, mini, d);
  EXPECT_TRUE(reversed.global.reversed);
  // The inlier figures are the caller's way: of the whole map's landmarks (more than the mini-map's could be), most
  // of which lie where the mini-map has nothing.
  EXPECT_GT(reversed.global.inliers, mini.landmarks.size());
  EXPECT_LT(reversed.global.inlier_fraction, 0.5);
  EXPECT_DOUBLE_EQ(reversed.global.inlier_fraction,
                   static_cast<double>(reversed.global.inliers) / static_cast<double>(whole.landmarks.size()));
  // The mini-map onto the whole map is searched as given.
  EXPECT_FALSE(expectRecovered(mini, whole, d).global.reversed);
  // The whole map searched as given (the search before) ends far off: the case above exercises the reversal.
  GlobalAlignmentSettings as_given;
  as_given.reverse_larger_source = false;
  GlobalLandmarkAligner aligner(as_given);
  aligner.setTarget(toLandmarkCloud(mini, CovarianceWeight{}));
  LandmarkMap moved = whole;
  moved.transform(d.toIsometry());
  const GlobalLandmarkAlignmentResult before = aligner.align(toLandmarkCloud(moved, CovarianceWeight{}));
  EXPECT_FALSE(before.global.reversed);
  EXPECT_GT(rotationErrorDeg(Eigen::Isometry3d(before.alignment.transformation), d.toIsometry().inverse()), 10.0);
}

TEST(GlobalAlignment, WithSearchSettingsSharesTheTargetAndRefusesSettingsThatShapeIt) {
  // Random landmarks in a 4 x 3 x 2 m room; the source the same points turned by 90 degrees and moved.
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> x(0.f, 4.f), y(0.f, 3.f), z(0.f, 2.f);
  GlobalAlignment::Cloud target, source;
  for (int i = 0; i < 400; ++i) target.push_back(pcl::PointXYZ(x(rng), y(rng), z(rng)));
  const Eigen::Isometry3d moved = Displacement{0.5, -0.3, 0.0, 0.0, 0.0, 90.0}.toIsometry();
  for (const auto& p : target) {
    const Eigen::Vector3d q = moved * Eigen::Vector3d(p.x, p.y, p.z);
    source.push_back(pcl::PointXYZ(static_cast<float>(q.x()), static_cast<float>(q.y()), static_cast<float>(q.z())));
  }
  GlobalAlignment full;
  full.setTarget(target);
  GlobalAlignmentSettings look = full.settings();
  look.refined_hypotheses = 3;
  look.climbed_hypotheses = 0;
  look.final_iterations = 20;
  const GlobalAlignment shared = full.withSearchSettings(look);
  GlobalAlignment own(look);
  own.setTarget(target);
  const GlobalAlignmentResult from_shared = shared.align(source), from_own = shared.align(source);
  EXPECT_TRUE(from_shared.transformation == own.align(source).transformation);  // the same target, bit for bit
  EXPECT_EQ(from_shared.inliers, from_own.inliers);
  EXPECT_LT(rotationErrorDeg(Eigen::Isometry3d(from_shared.transformation), moved.inverse()), 1.0);

  // A new target for the first aligner leaves the copy's as it was.
  GlobalAlignment::Cloud elsewhere = target;
  for (auto& p : elsewhere) p.x += 10.f;
  full.setTarget(elsewhere);
  EXPECT_TRUE(shared.align(source).transformation == from_shared.transformation);

  for (const char* name : {"sample_cell", "max_target_samples", "fine_window", "medium_cell"}) {
    GlobalAlignmentSettings other = full.settings();
    if (std::string(name) == "sample_cell") other.sample_cell = 0.3;
    if (std::string(name) == "max_target_samples") other.max_target_samples = 100;
    if (std::string(name) == "fine_window") other.fine_window *= 2.0;
    if (std::string(name) == "medium_cell") other.medium_cell *= 2.0;
    try {
      full.withSearchSettings(other);
      ADD_FAILURE() << name << " changed and accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(GlobalAlignment{}.withSearchSettings(look).align(source), std::invalid_argument);  // no target yet
}

TEST(GlobalAlignment, BadInputIsRefusedWithAClearMessage) {
  GlobalAlignment::Cloud two;
  two.push_back(pcl::PointXYZ(0, 0, 0));
  two.push_back(pcl::PointXYZ(1, 0, 0));
  GlobalAlignment global;
  EXPECT_THROW(global.align(two), std::invalid_argument);  // no target yet
  try {
    global.setTarget(two);
    ADD_FAILURE() << "two points accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("fewer than 3"), std::string::npos) << e.what();
  }
  GlobalAlignment::Cloud same;
  for (int i = 0; i < 5; ++i) same.push_back(pcl::PointXYZ(1, 2, 3));
  EXPECT_THROW(global.setTarget(same), std::invalid_argument);
  GlobalAlignment::Cloud nans = same;
  for (auto& p : nans) p.x = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(global.setTarget(nans), std::invalid_argument);

  GlobalAlignmentSettings settings;
  settings.yaw_hypotheses = 0;
  EXPECT_THROW(GlobalAlignment{settings}, std::invalid_argument);
  settings = {};
  settings.fine_cell = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(GlobalAlignment{settings}, std::invalid_argument);
  settings = {};
  settings.up_axis = Eigen::Vector3d::Zero();
  EXPECT_THROW(GlobalAlignment{settings}, std::invalid_argument);
  settings = {};
  settings.final_tilt_step_deg = 0.2;  // 20 steps each way for the default 4° range
  try {
    GlobalAlignment{settings};
    ADD_FAILURE() << "final tilts of 20 steps each way accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("final_tilt_step_deg"), std::string::npos) << e.what();
  }
  settings.final_tilt_range_deg = 0.0;  // no final tilts: the step is not used up
  EXPECT_NO_THROW(GlobalAlignment{settings});
  for (const unsigned int rounds : {0u, 11u}) {
    settings = {};
    settings.final_tilt_rounds = rounds;
    try {
      GlobalAlignment{settings};
      ADD_FAILURE() << rounds << " rounds of final tilts accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("final_tilt_rounds"), std::string::npos) << e.what();
    }
  }

  GlobalLandmarkAligner landmarks;
  EXPECT_THROW(landmarks.setTarget(std::make_shared<LandmarkCloud>()), std::invalid_argument);
  EXPECT_THROW(landmarks.align(std::make_shared<LandmarkCloud>()), std::invalid_argument);
}

}  // namespace
