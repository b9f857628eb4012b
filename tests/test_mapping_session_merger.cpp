// mergeSessions at the library level: two sessions of the larger room (true poses), the second one's world moved
// elsewhere; the link found by agreeing loops, then the other keyframes verified with the link as prior, every loop
// right. And KeyframeSnapshot::pathLength, which bounds that prior.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "mapping_fixtures.h"
#include "weighted_icp/mapping/session.h"
#include "weighted_icp/mapping/session_merger.h"

namespace weighted_icp::mapping {
namespace {

constexpr double kDegree = M_PI / 180.0;
constexpr std::uint64_t kStride = MiniMapGraph::kSessionIdStride;

/// Keyframes at their true poses as a saved session holds them (one frame per keyframe), the world moved by
/// `motion` (a session started elsewhere).
Session asSession(const testing::SyntheticKeyframes& data, const Eigen::Isometry3d& motion) {
  Session session;
  session.camera = data.camera;
  for (const auto& [id, keyframe] : data.snapshot.keyframes) {
    session.keyframes.push_back(keyframe);
    session.keyframes.back().pose_wc = motion * keyframe.pose_wc;
    session.frames.push_back({keyframe.timestamp, id, Eigen::Isometry3d::Identity()});
  }
  for (const auto& [id, point] : data.snapshot.points) {
    session.points.push_back(point);
    session.points.back().position = motion * point.position;
    session.points.back().covariance = motion.linear() * point.covariance * motion.linear().transpose();
  }
  session.validate();
  return session;
}

struct LargeRoomSessions {
  std::vector<Session> sessions;
  testing::SyntheticKeyframes first, second;
  Eigen::Isometry3d second_world_in_first;
};

/// The larger room's first 220 frames, and frames 200-430: the two overlap where one ends and the other starts,
/// and again where the camera comes back to the room's start at the end of the lap.
const LargeRoomSessions& largeRoomSessions() {
  static const LargeRoomSessions data = [] {
    constexpr double kLargeRoom = 2.0, kLargeLoop = 360.0;  // a lap of 360 frames
    constexpr std::size_t kEvery = 9;
    LargeRoomSessions d{
        {},
        testing::syntheticKeyframes(7, false, kLargeLoop, testing::everyNth(221, kEvery), kLargeRoom),
        testing::syntheticKeyframes(7, false, kLargeLoop, testing::everyNth(431, kEvery, 200), kLargeRoom),
        Eigen::Isometry3d::Identity()};
    Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
    motion.linear() = Eigen::AngleAxisd(120.0 * kDegree, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    motion.translation() = Eigen::Vector3d(2.0, -1.0, 0.2);
    d.sessions = {asSession(d.first, Eigen::Isometry3d::Identity()), asSession(d.second, motion)};
    d.second_world_in_first = motion.inverse();
    return d;
  }();
  return data;
}

/// Largest error of the merge's loops against the true relative poses (metres, degrees).
std::pair<double, double> worstLoopError(const SessionMerge& merge, const LargeRoomSessions& data) {
  double metres = 0.0, degrees = 0.0;
  for (const LoopConstraint& loop : merge.loops) {
    const auto& query = data.second.snapshot.keyframes.at(loop.query % kStride);
    const auto& match = data.first.snapshot.keyframes.at(loop.match % kStride);
    const Eigen::Isometry3d error = (match.pose_wc.inverse() * query.pose_wc).inverse() * loop.query_in_match;
    metres = std::max(metres, error.translation().norm());
    degrees = std::max(degrees, Eigen::AngleAxisd(error.linear()).angle() / kDegree);
  }
  return {metres, degrees};
}

TEST(SessionMerger, VerifiesTheOtherKeyframesAgainWithTheLinkAsPrior) {
  const LargeRoomSessions& data = largeRoomSessions();
  SessionMergeOptions options;
  // Loops agree only within 1 cm / 0.2 degrees: the link rests on fewer of them, the others are left to the second
  // pass (as the weighted check without a prior leaves them in a larger room, LoopVerification tests).
  options.agreement_translation_m = 0.01;
  options.agreement_rotation_deg = 0.2;
  options.loops_with_link_prior = false;
  const SessionMerge agreeing_only = mergeSessions(data.sessions, testing::trainedVocabulary(), options);
  ASSERT_TRUE(agreeing_only.sessions[1].merged) << "the first pass must link the sessions for the test to say anything";
  EXPECT_EQ(agreeing_only.sessions[1].loops_with_link_prior, 0u);

  options.loops_with_link_prior = true;
  std::map<std::string, std::pair<std::size_t, std::size_t>> passes;  // pass -> last (done, total)
  options.progress = [&](const std::string& pass, std::size_t done, std::size_t total) {
    EXPECT_LE(done, total) << pass;
    passes[pass] = {done, total};
  };
  const SessionMerge merge = mergeSessions(data.sessions, testing::trainedVocabulary(), options);
  // Progress: both passes reported, each to its end; the second one over the keyframes no agreeing loop holds.
  ASSERT_EQ(passes.size(), 2u);
  const auto first = passes.find("session 1 against 0");
  const auto second = passes.find("session 1 against 0 with the link as prior");
  ASSERT_NE(first, passes.end());
  ASSERT_NE(second, passes.end());
  EXPECT_EQ(first->second.first, first->second.second);
  EXPECT_EQ(first->second.second, data.sessions[1].keyframes.size());
  EXPECT_EQ(second->second.first, second->second.second);
  EXPECT_LT(second->second.second, first->second.second);
  ASSERT_TRUE(merge.sessions[1].merged);
  EXPECT_FALSE(merge.sessions[1].free_space_optimised);  // a session true to itself lies on the other rigidly
  EXPECT_GT(merge.sessions[1].loops_with_link_prior, 0u) << "no keyframe was verified again";
  EXPECT_EQ(merge.loops.size(), agreeing_only.loops.size() + merge.sessions[1].loops_with_link_prior);
  ASSERT_EQ(merge.loop_used.size(), merge.loops.size());
  EXPECT_EQ(static_cast<std::size_t>(std::count(merge.loop_used.begin(), merge.loop_used.end(), true)),
            merge.summary.loops_used);
  const auto [metres, degrees] = worstLoopError(merge, data);
  EXPECT_LT(metres, 0.03);
  EXPECT_LT(degrees, 0.5);
  // The second session's world lands where the truth puts it.
  const Eigen::Isometry3d error = data.second_world_in_first.inverse() * merge.sessions[1].world_in_first;
  EXPECT_LT(error.translation().norm(), 0.02);
  EXPECT_LT(Eigen::AngleAxisd(error.linear()).angle() / kDegree, 0.5);
}

/// The second session bent in its middle: keyframes 5-15 turn, step by step, by `degrees` about keyframe 10, and
/// those after them (their landmarks with them) stay turned: each end rigid in itself, the two ends `degrees` apart.
std::vector<Session> bentSessions(double degrees) {
  std::vector<Session> sessions = largeRoomSessions().sessions;
  Session& bent = sessions[1];
  const Eigen::Vector3d centre = bent.keyframes.at(10).pose_wc.translation();
  std::map<frontend::KeyframeId, Eigen::Isometry3d> turn;
  for (std::size_t k = 0; k < bent.keyframes.size(); ++k) {
    const double part = std::clamp((static_cast<double>(k) - 5.0) / 10.0, 0.0, 1.0);
    Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
    motion.linear() = Eigen::AngleAxisd(degrees * kDegree * part, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    motion.translation() = centre - motion.linear() * centre;
    turn[bent.keyframes[k].id] = motion;
    bent.keyframes[k].pose_wc = motion * bent.keyframes[k].pose_wc;
  }
  for (auto& point : bent.points)
    if (!point.observations.empty()) point.position = turn.at(point.observations.front().keyframe) * point.position;
  return sessions;
}

TEST(SessionMerger, ASessionThatDriftedWithinItselfIsJudgedAsTheJointGraphLaysIt) {
  // Bent by 5 degrees, no single loop's transform lays the second map on the first one: 5.4 % of the landmarks in
  // the other's free space, refused until 2026-11-29. Optimised with its loops at both ends (agreement widened so
  // that the two ends' loops agree, as the real case's did within the defaults), 0.15 %.
  SessionMergeOptions options;
  options.agreement_translation_m = 0.6;
  options.agreement_rotation_deg = 10.0;
  options.loops_with_link_prior = false;
  const SessionMerge merge = mergeSessions(bentSessions(5.0), testing::trainedVocabulary(), options);
  const SessionLink& link = merge.sessions[1];
  EXPECT_EQ(link.loops_agreeing, link.loops_found);
  ASSERT_GE(link.loops_agreeing, 10u) << "loops at both ends of the bend must agree for the test to say anything";
  EXPECT_TRUE(link.merged) << "free space " << link.free_space_violation;
  EXPECT_TRUE(link.free_space_optimised);
  EXPECT_GT(link.free_space_rigid_violation, options.max_free_space_violation);
  EXPECT_LT(link.free_space_violation, 0.005);

  // Its unbent start (keyframes 0-5) lands where the truth puts it.
  const Eigen::Isometry3d error = largeRoomSessions().second_world_in_first.inverse() * link.world_in_first;
  EXPECT_LT(error.translation().norm(), 0.03);
  EXPECT_LT(Eigen::AngleAxisd(error.linear()).angle() / kDegree, 0.5);
}

TEST(KeyframeSnapshot, PathLengthSumsTheStepsBetweenTwoKeyframesEitherWay) {
  const testing::SyntheticKeyframes first = testing::syntheticKeyframes(7, false, 180.0, {0, 6, 12, 18});
  const auto& keyframes = first.snapshot.keyframes;
  const double steps = (keyframes.at(1).pose_wc.translation() - keyframes.at(0).pose_wc.translation()).norm() +
                       (keyframes.at(2).pose_wc.translation() - keyframes.at(1).pose_wc.translation()).norm();
  EXPECT_GT(steps, 0.0);
  EXPECT_DOUBLE_EQ(first.snapshot.pathLength(0, 2), steps);
  EXPECT_DOUBLE_EQ(first.snapshot.pathLength(2, 0), steps);
  EXPECT_EQ(first.snapshot.pathLength(3, 3), 0.0);
  EXPECT_THROW(first.snapshot.pathLength(0, 100000), std::invalid_argument);
}

}  // namespace
}  // namespace weighted_icp::mapping
