// Place recognition and loop verification on synthetic loops with true poses:
// the known revisit is found and verified, places never revisited are
// refused (also under perceptual aliasing), and verification recovers the
// relative pose whatever the rotation between the two maps.

#include <algorithm>
#include <cmath>
#include <iostream>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>

#include "mapping_fixtures.h"
#include "weighted_icp/mapping/loop_verifier.h"
#include "weighted_icp/mapping/place_recognizer.h"
#include "weighted_icp/mapping/view_overlap.h"

namespace weighted_icp::mapping {
namespace {

constexpr double kDegree = 3.14159265358979323846 / 180.0;
// The loops: once round in 180 frames, keyframes every 6 frames, on to frame 228 (frames 180-228 revisit 0-48).
constexpr double kFramesPerLoop = 180.0;
constexpr std::size_t kFrames = 228, kEvery = 6;

/// How far a relative pose is from the truth: metres and degrees.
std::pair<double, double> poseError(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& truth) {
  const Eigen::Isometry3d error = truth.inverse() * estimate;
  return {error.translation().norm(), Eigen::AngleAxisd(error.linear()).angle() / kDegree};
}

Eigen::Isometry3d trueQueryInMatch(const KeyframeSnapshot& map, frontend::KeyframeId query,
                                   frontend::KeyframeId match) {
  return map.keyframes.at(match).pose_wc.inverse() * map.keyframes.at(query).pose_wc;
}

struct Verified {
  frontend::KeyframeId query, match;
  LoopVerification result;
};

/// The loop closer's steps, keyframe after keyframe: query the database, verify what passed temporal
/// consistency (with the odometry prior; here the poses are true), then add the keyframe.
std::vector<Verified> detectLoops(const testing::SyntheticKeyframes& data) {
  PlaceRecognizer recognizer(testing::trainedVocabulary());
  const LoopVerifier verifier(data.camera);
  std::vector<Verified> verified;
  for (const auto& [id, keyframe] : data.snapshot.keyframes) {
    const BowVector bow = recognizer.vocabulary().transform(keyframe.descriptors);
    for (const PlaceCandidate& candidate : recognizer.detect(id, bow, data.snapshot.covisible(id)))
      verified.push_back({id, candidate.keyframe,
                          verifier.verify(data.snapshot, id, data.snapshot, candidate.keyframe,
                                          odometryPrior(data.snapshot, id, candidate.keyframe))});
    recognizer.add(id, bow);
  }
  return verified;
}

TEST(LoopDetection, FindsTheKnownRevisitAndRefusesNonRevisits) {
  const auto data = testing::syntheticKeyframes(7, false, kFramesPerLoop, testing::everyNth(kFrames, kEvery));
  const std::vector<Verified> loops = detectLoops(data);
  std::size_t accepted = 0, refused_false = 0;
  for (const Verified& loop : loops) {
    const double overlap = viewOverlap(data.snapshot, loop.query, loop.match, data.camera);
    if (!loop.result.accepted) {
      std::cout << "refused " << loop.query << " -> " << loop.match << " overlap " << overlap << ": "
                << loop.result.reason << "\n";
      refused_false += overlap < 0.1;
      continue;
    }
    ++accepted;
    // Every accepted loop is a true revisit (the views share more than the tenth below which a refusal counts as a
    // non-revisit; one loop checked by plain ICP shares 16 %), with the true relative pose to far better than the
    // drift a loop corrects (the odometry prior allows 0.3 m and 10 degrees and more).
    EXPECT_GT(overlap, 0.1) << loop.query << " -> " << loop.match;
    const auto [metres, degrees] = poseError(loop.result.constraint.query_in_match,
                                             trueQueryInMatch(data.snapshot, loop.query, loop.result.constraint.match));
    EXPECT_LT(metres, 0.05) << loop.query << " -> " << loop.match;
    EXPECT_LT(degrees, 2.0) << loop.query << " -> " << loop.match;
    EXPECT_GE(loop.result.constraint.inliers, LoopVerificationOptions{}.min_inliers);
    EXPECT_GT(loop.result.constraint.information.determinant(), 0.0);
    std::cout << "accepted " << loop.query << " -> " << loop.match << ": " << metres << " m, " << degrees << " deg\n";
  }
  // The camera comes back for the last eight keyframes: most of them must close the loop.
  EXPECT_GE(accepted, 4u);
  // Appearance alone proposed places the camera never revisited, and verification refused them.
  EXPECT_GE(refused_false, 1u);

  // A place never revisited, verified directly: the query sees the opposite side of the room.
  const frontend::KeyframeId query = data.snapshot.keyframes.rbegin()->first;  // frame 222, near frame 42
  const frontend::KeyframeId opposite = 15;                                    // frame 90, half a loop away
  ASSERT_LT(viewOverlap(data.snapshot, query, opposite, data.camera), 0.05);
  const LoopVerifier verifier(data.camera);
  EXPECT_FALSE(verifier.verify(data.snapshot, query, data.snapshot, opposite).accepted);
  EXPECT_FALSE(
      verifier.verify(data.snapshot, query, data.snapshot, opposite, odometryPrior(data.snapshot, query, opposite))
          .accepted);
}

TEST(LoopDetection, RepeatedTextureLeadsToNoFalseLoop) {
  // Every face shows the same wallpaper: appearance, and even the local geometry of a room corner, cannot
  // tell places apart; the odometry prior refuses what would need a 90-degree drift.
  const auto data = testing::syntheticKeyframes(7, true, kFramesPerLoop, testing::everyNth(kFrames, kEvery));
  const std::vector<Verified> loops = detectLoops(data);
  std::size_t false_candidates = 0;
  for (const Verified& loop : loops) {
    const double overlap = viewOverlap(data.snapshot, loop.query, loop.match, data.camera);
    false_candidates += overlap < 0.1;
    if (!loop.result.accepted) continue;
    const auto [metres, degrees] = poseError(loop.result.constraint.query_in_match,
                                             trueQueryInMatch(data.snapshot, loop.query, loop.result.constraint.match));
    EXPECT_LT(metres, 0.05) << "false loop " << loop.query << " -> " << loop.match;
    EXPECT_LT(degrees, 2.0) << "false loop " << loop.query << " -> " << loop.match;
  }
  EXPECT_GE(false_candidates, 1u) << "the aliasing did not fool appearance: the test proves nothing";
}

/// The same keyframes and landmarks, moved rigidly (as a second session started elsewhere would be).
KeyframeSnapshot moved(const KeyframeSnapshot& map, const Eigen::Isometry3d& motion) {
  KeyframeSnapshot result = map;
  for (auto& [id, keyframe] : result.keyframes) keyframe.pose_wc = motion * keyframe.pose_wc;
  for (auto& [id, point] : result.points) {
    point.position = motion * point.position;
    point.covariance = motion.linear() * point.covariance * motion.linear().transpose();
  }
  return result;
}

/// Keyframes at the start (frames 0-30, ids 0-5) and where the camera comes back (frames 180-210, ids 6-11): keyframe 8
/// (frame 192) sees the place of keyframe 2 (frame 12).
testing::SyntheticKeyframes startAndReturn() {
  std::vector<std::size_t> frames = testing::everyNth(36, kEvery);
  for (std::size_t f : testing::everyNth(216, kEvery, 180)) frames.push_back(f);
  return testing::syntheticKeyframes(11, false, kFramesPerLoop, frames);
}

TEST(LoopVerification, RecoversTheRelativePoseAtAnyYaw) {
  const auto data = startAndReturn();
  const frontend::KeyframeId match = 2;  // frame 12
  const frontend::KeyframeId query = 8;  // frame 192
  ASSERT_GT(viewOverlap(data.snapshot, query, match, data.camera), 0.5);
  const LoopVerifier verifier(data.camera);
  for (double yaw_deg : {0.0, 90.0, 180.0, -135.0}) {
    SCOPED_TRACE("yaw " + std::to_string(yaw_deg));
    Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
    motion.linear() = Eigen::AngleAxisd(yaw_deg * kDegree, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
                      Eigen::AngleAxisd(10.0 * kDegree, Eigen::Vector3d::UnitX()).toRotationMatrix();
    motion.translation() = Eigen::Vector3d(1.5, -2.0, 0.3);
    const KeyframeSnapshot query_map = moved(data.snapshot, motion);
    const LoopVerification result = verifier.verify(query_map, query, data.snapshot, match);
    ASSERT_TRUE(result.accepted) << result.reason;
    const auto [metres, degrees] =
        poseError(result.constraint.query_in_match, trueQueryInMatch(data.snapshot, query, result.constraint.match));
    EXPECT_LT(metres, 0.02);
    EXPECT_LT(degrees, 0.5);
    EXPECT_EQ(result.constraint.query, query);
    // The candidate, or the neighbour of its mini-map that saw more of PnP's inliers.
    EXPECT_LE(std::abs(static_cast<int>(result.constraint.match) - static_cast<int>(match)),
              static_cast<int>(LoopVerificationOptions{}.neighbour_keyframes));
    // The information matrix is symmetric positive definite.
    const Eigen::Matrix<double, 6, 6>& information = result.constraint.information;
    EXPECT_LT((information - information.transpose()).norm(), 1e-9 * information.norm());
    using Solver = Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>>;
    EXPECT_GT(Solver(information).eigenvalues().minCoeff(), 0.0);
  }
}

TEST(LoopVerification, WithoutTheIcpCheckTheGeometryIsJudgedAtPnpsPose) {
  // As a segment bridge verifies: the overlap and fitness at PnP's pose, no ICP moving it. A true loop passes; a
  // query map whose landmarks are 35 cm off its keyframes (PnP, on the match map's landmarks and the query's pixels,
  // still finds the camera) does not overlap there.
  const auto data = startAndReturn();
  const frontend::KeyframeId match = 2, query = 8;
  LoopVerificationOptions options;
  options.icp_check = false;
  const LoopVerifier verifier(data.camera, options);
  const LoopVerification result = verifier.verify(data.snapshot, query, data.snapshot, match);
  ASSERT_TRUE(result.accepted) << result.reason;
  EXPECT_EQ(result.icp_correction_m, 0.0);
  EXPECT_FALSE(result.icp_weighted);
  const Eigen::Isometry3d edge_in_match =
      data.snapshot.keyframes.at(match).pose_wc.inverse() * data.snapshot.keyframes.at(result.constraint.match).pose_wc;
  EXPECT_TRUE((edge_in_match * result.constraint.query_in_match).isApprox(result.pnp_query_in_match, 1e-9))
      << "the edge is PnP's pose";
  const auto [metres, degrees] =
      poseError(result.constraint.query_in_match, trueQueryInMatch(data.snapshot, query, result.constraint.match));
  EXPECT_LT(metres, 0.02);
  EXPECT_LT(degrees, 0.5);
  KeyframeSnapshot displaced = data.snapshot;  // the query's map: its landmarks 35 cm off, its keyframes not
  for (auto& [id, point] : displaced.points) point.position += Eigen::Vector3d(0.2, 0.2, 0.2);  // off every wall
  const LoopVerification refused = verifier.verify(displaced, query, data.snapshot, match);
  EXPECT_FALSE(refused.accepted);
  EXPECT_EQ(refused.refused_by, "overlap") << refused.reason;
}

TEST(LoopVerification, AnIcpWithinTheCorrectionBoundConfirmsAPnpEdgeWithoutReproducingItsPixels) {
  // The query's landmarks turned 1 degree about its camera, its keyframes and features not: PnP (the query's pixels
  // on the candidate's landmarks) still finds the camera, the landmark clouds put it about a degree away. As the
  // clouds of frames taken in the dark do: well within the 2 degrees that make a loop wrong, yet the ICP's pose
  // projects few of PnP's inliers within its 3 px. With the PnP edge (the default) the ICP only checks the pose and
  // the loop stands; with the ICP edge its pose would be the loop, and must explain the descriptor matches.
  const auto data = startAndReturn();
  const frontend::KeyframeId match = 2, query = 8;
  const Eigen::Vector3d centre = data.snapshot.keyframes.at(query).pose_wc.translation();
  const Eigen::Isometry3d turn = Eigen::Translation3d(centre) *
                                 Eigen::AngleAxisd(1.0 * kDegree, Eigen::Vector3d::UnitZ()) *
                                 Eigen::Translation3d(-centre);
  KeyframeSnapshot turned = data.snapshot;
  for (auto& [id, point] : turned.points) {
    point.position = turn * point.position;
    point.covariance = turn.linear() * point.covariance * turn.linear().transpose();
  }
  const LoopVerifier verifier(data.camera);
  const LoopVerification result = verifier.verify(turned, query, data.snapshot, match);
  ASSERT_TRUE(result.accepted) << result.reason;
  EXPECT_GT(result.icp_correction_deg, 0.5) << "the ICP did not see the turn: the test proves nothing";
  EXPECT_LT(result.icp_explained_inliers, verifier.options().min_inliers)
      << "the ICP's pose still reproduces PnP's pixels: the test proves nothing";
  const auto [metres, degrees] =
      poseError(result.constraint.query_in_match, trueQueryInMatch(data.snapshot, query, result.constraint.match));
  EXPECT_LT(metres, 0.02) << "the edge is PnP's pose";
  EXPECT_LT(degrees, 0.5);
  LoopVerificationOptions icp_edge;
  icp_edge.edge = LoopEdgeSource::Icp;
  const LoopVerification refused = LoopVerifier(data.camera, icp_edge).verify(turned, query, data.snapshot, match);
  EXPECT_FALSE(refused.accepted);
  EXPECT_EQ(refused.refused_by, "icp_inliers") << refused.reason;
}

TEST(LoopVerification, APnpLoopJoinsTheKeyframeThatSawItsInliers) {
  // As in the dark, where keyframes share few landmarks: the candidate's pose has drifted 8 cm and 3 degrees from
  // its neighbours' and it saw none of the landmarks PnP placed the query by (its observations taken out of every
  // landmark another keyframe saw too). PnP finds the query camera among its neighbours' landmarks; relative to the
  // candidate that pose carries the drift, relative to the neighbour that saw the most of its inliers it does not.
  const auto data = startAndReturn();
  const frontend::KeyframeId match = 2, query = 8;
  KeyframeSnapshot drifted = data.snapshot;
  Eigen::Isometry3d drift = Eigen::Isometry3d::Identity();
  drift.linear() = Eigen::AngleAxisd(3.0 * kDegree, Eigen::Vector3d::UnitY()).toRotationMatrix();
  drift.translation() = Eigen::Vector3d(0.08, 0.0, 0.0);
  drifted.keyframes.at(match).pose_wc = drifted.keyframes.at(match).pose_wc * drift;
  for (auto& [id, point] : drifted.points) {
    auto& observations = point.observations;
    if (observations.size() < 2) continue;
    observations.erase(std::remove_if(observations.begin(), observations.end(),
                                      [&](const frontend::MapPointObservation& o) { return o.keyframe == match; }),
                       observations.end());
  }
  const LoopVerifier verifier(data.camera);
  const LoopVerification result = verifier.verify(drifted, query, drifted, match);
  ASSERT_TRUE(result.accepted) << result.reason;
  EXPECT_NE(result.constraint.match, match);
  EXPECT_LE(std::abs(static_cast<int>(result.constraint.match) - static_cast<int>(match)),
            static_cast<int>(verifier.options().neighbour_keyframes));
  const auto [metres, degrees] =
      poseError(result.constraint.query_in_match, trueQueryInMatch(data.snapshot, query, result.constraint.match));
  EXPECT_LT(metres, 0.02);
  EXPECT_LT(degrees, 0.5);
  // What an edge to the candidate would have been: PnP's pose relative to its drifted pose.
  const auto [candidate_metres, candidate_degrees] =
      poseError(result.pnp_query_in_match, trueQueryInMatch(data.snapshot, query, match));
  EXPECT_GT(candidate_degrees, 2.0) << candidate_metres << " m";
}

TEST(LoopVerification, AnIcpThatLeavesThePnpPoseDoesNotRefuseATrueLoop) {
  // A room three times as large: landmarks metres apart on far walls, where the weighted stage's choice of the most
  // confident neighbour pulled the same way at every iteration and slid 1.3 m away from a PnP pose right to 1 cm.
  constexpr double kLargeRoom = 3.0, kLargeLoop = 540.0;
  std::vector<std::size_t> frames = testing::everyNth(36, kEvery);
  for (std::size_t f : testing::everyNth(576, kEvery, 540)) frames.push_back(f);
  const auto data = testing::syntheticKeyframes(7, false, kLargeLoop, frames, kLargeRoom);
  const frontend::KeyframeId match = 2;  // frame 12
  const frontend::KeyframeId query = 8;  // frame 552
  const LoopVerifier verifier(data.camera);
  // Within a session, as the loop detector verifies (the odometry prior of the keyframes' poses).
  const LoopVerification result =
      verifier.verify(data.snapshot, query, data.snapshot, match, odometryPrior(data.snapshot, query, match));
  ASSERT_TRUE(result.accepted) << result.reason;
  EXPECT_FALSE(result.icp_weighted) << "the weighted stage left PnP's pose; plain ICP checked it";
  const auto [metres, degrees] =
      poseError(result.constraint.query_in_match, trueQueryInMatch(data.snapshot, query, result.constraint.match));
  EXPECT_LT(metres, 0.02);
  EXPECT_LT(degrees, 0.5);
  EXPECT_GT(result.overlap, 0.5) << "judged where the clouds overlap";
  EXPECT_LT(result.icp_correction_m, 0.05);
  // Without a prior (sessions being merged) the weighted stage's disagreement stands.
  EXPECT_FALSE(verifier.verify(data.snapshot, query, data.snapshot, match).accepted);
}

/// A small vocabulary trained on two images far apart in Hamming space (half their bits differ on purpose), so that
/// their words differ and weigh something (IDF); `descriptors` is the first image.
BinaryVocabulary::ConstPtr twoImageVocabulary(cv::Mat& descriptors) {
  VocabularyTrainingOptions options;
  options.branching = 4;
  options.depth = 2;
  descriptors.create(64, 32, CV_8U);
  cv::randu(descriptors, 0, 256);
  cv::Mat others(64, 32, CV_8U);
  cv::randu(others, 0, 256);
  descriptors.colRange(0, 16).setTo(0);
  others.colRange(0, 16).setTo(255);
  return std::make_shared<const BinaryVocabulary>(BinaryVocabulary::train({descriptors, others}, options));
}

/// Place recognition with every score admitted, so that only the exclusions and the consistency decide.
PlaceRecognitionOptions admittingEveryScore(std::size_t exclude_recent, std::size_t consistent_queries) {
  PlaceRecognitionOptions place;
  place.exclude_recent = exclude_recent;
  place.consistent_queries = consistent_queries;
  place.min_normalised_score = 0.0;
  return place;
}

TEST(PlaceRecognition, ExcludesRecentAndCovisibleKeyframesAndWaitsForConsistency) {
  cv::Mat descriptors;
  const auto vocabulary = twoImageVocabulary(descriptors);
  PlaceRecognizer recognizer(vocabulary, admittingEveryScore(2, 2));
  for (frontend::KeyframeId id = 0; id < 5; ++id) recognizer.add(id, descriptors);
  const BowVector bow = vocabulary->transform(descriptors);
  // Keyframe 4 is recent for query 6; keyframe 1 shares landmarks with it.
  const auto ranked = recognizer.rank(6, bow, {1});
  std::vector<frontend::KeyframeId> ids;
  for (const PlaceCandidate& c : ranked) ids.push_back(c.keyframe);
  EXPECT_EQ(ids, (std::vector<frontend::KeyframeId>{0, 2, 3}));
  // The first query only starts a chain; the next one, agreeing, completes it.
  EXPECT_TRUE(recognizer.detect(6, bow, {}).empty());
  const auto detected = recognizer.detect(7, bow, {});
  ASSERT_EQ(detected.size(), 1u);
  EXPECT_EQ(detected.front().consistent_queries, 2u);
  EXPECT_LE(detected.front().keyframe, 4u);
  // A query that finds nothing breaks the chain.
  EXPECT_TRUE(recognizer.detect(8, {}, {}).empty());
  EXPECT_TRUE(recognizer.detect(9, bow, {}).empty());
  EXPECT_THROW(PlaceRecognizer(nullptr), std::invalid_argument);
}

TEST(PlaceRecognition, ProposesRecentKeyframesOfAnotherSegment) {
  // Tracking links a keyframe to the recent ones of its own segment only: across a tracking loss the keyframes
  // just before it are candidates.
  cv::Mat descriptors;
  const auto vocabulary = twoImageVocabulary(descriptors);
  PlaceRecognizer recognizer(vocabulary, admittingEveryScore(5, 3));
  for (frontend::KeyframeId id = 0; id < 3; ++id) recognizer.add(id, descriptors, 0);
  recognizer.add(3, descriptors, 1);
  const BowVector bow = vocabulary->transform(descriptors);
  const auto ids = [&](std::size_t segment) {
    std::vector<frontend::KeyframeId> result;
    for (const PlaceCandidate& c : recognizer.rank(4, bow, {}, segment)) result.push_back(c.keyframe);
    std::sort(result.begin(), result.end());
    return result;
  };
  EXPECT_EQ(ids(1), (std::vector<frontend::KeyframeId>{0, 1, 2}));  // query in segment 1: segment 0 is not recent
  EXPECT_EQ(ids(0), (std::vector<frontend::KeyframeId>{3}));
  EXPECT_EQ(ids(2).size(), 4u);  // a third segment: none is recent
}

}  // namespace
}  // namespace weighted_icp::mapping
