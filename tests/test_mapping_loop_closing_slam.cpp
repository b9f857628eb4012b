// LoopClosingSlam on a synthetic RGB-D sequence: a scripted loop's correction is applied between frames, tracking
// carries on from the corrected map without a jump, and the session of the run round-trips.
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "test_support.h"
#include "weighted_icp/mapping/loop_closing_slam.h"
#include "weighted_icp/mapping/minimap_graph.h"
#include "weighted_icp/mapping/session.h"
#include "weighted_icp/simulation/rgbd_sequence.h"

namespace weighted_icp::testing {
namespace {

/// A world-frame shift of 5 cm and 2 degrees: what the scripted loop says keyframe 3 is off by.
Eigen::Isometry3d scriptedOffset() {
  Eigen::Isometry3d offset = Eigen::Isometry3d::Identity();
  offset.linear() = Eigen::AngleAxisd(2.0 * M_PI / 180, Eigen::Vector3d::UnitY()).toRotationMatrix();
  offset.translation() = Eigen::Vector3d(0.05, 0.0, 0.0);
  return offset;
}

mapping::LoopClosingSlamOptions inlineOptions() {
  mapping::LoopClosingSlamOptions options;
  options.slam.backend.background_thread = false;
  options.loop_closing.background_thread = false;
  // The scripted loop is not a real one: it must be taken whatever the odometry says.
  options.loop_closing.pose_graph.loop_chi2_gate = std::numeric_limits<double>::infinity();
  // And outweigh the odometry: with the loose noise model its information of 1e10 does, even through the loop
  // edges' Huber loss; odometry information from tracking (millimetres) would hold keyframe 3 back.
  options.odometry_from_tracking = false;
  return options;
}

TEST(LoopClosingSlam, AnAcceptedLoopIsAppliedAtTheNextFrameAndTheRunSavesAsASession) {
  simulation::SyntheticRgbdOptions sequence_options;
  sequence_options.frames = 40;
  const simulation::SyntheticRgbdSequence sequence(sequence_options);

  // At keyframe 3: "keyframe 2 sees you 5 cm and 2 degrees from where you think you are", and far more sure of it
  // than the odometry, so the pose graph moves keyframe 3 (the chain's end) by that much.
  mapping::LoopDetector detector = [](const frontend::Map& map,
                                      frontend::KeyframeId query) -> std::optional<mapping::LoopConstraint> {
    if (query != 3) return std::nullopt;
    mapping::LoopConstraint loop;
    loop.query = 3;
    loop.match = 2;
    loop.query_in_match = map.keyframePose(2)->inverse() * scriptedOffset() * *map.keyframePose(3);
    loop.information = Eigen::Matrix<double, 6, 6>::Identity() * 1e10;
    return loop;
  };
  mapping::LoopClosingSlam slam(sequence.options().camera, detector, inlineOptions());
  std::optional<std::size_t> loop_frame;
  std::optional<Eigen::Isometry3d> keyframe_3_before;
  for (std::size_t i = 0; i < sequence.size(); ++i) {
    const auto& record = slam.process(sequence.frame(i).rgbd);
    ASSERT_TRUE(record.result.hasPose()) << "frame " << i << ": " << record.result.reason;
    if (record.result.keyframe && record.result.reference_keyframe == 3) {
      loop_frame = i;
      keyframe_3_before = slam.slam().map().keyframePose(3);
      // The correction waits for the next frame, which applies it before tracking.
      EXPECT_TRUE(slam.slam().map().correctionPending());
      EXPECT_EQ(slam.slam().map().corrections(), 0u);
    } else if (loop_frame && i == *loop_frame + 1) {
      EXPECT_EQ(slam.slam().map().corrections(), 1u);
      const Eigen::Isometry3d expected = scriptedOffset() * *keyframe_3_before;
      EXPECT_LT((slam.slam().map().keyframePose(3)->translation() - expected.translation()).norm(), 1e-3);
    }
  }
  slam.finish();
  ASSERT_TRUE(loop_frame) << "the sequence must make at least 4 keyframes";
  const auto stats = slam.loopStats();
  EXPECT_EQ(stats.loops_detected, 1u);
  EXPECT_EQ(stats.loops_accepted, 1u);
  EXPECT_EQ(stats.pose_graph_optimisations, 1u);
  ASSERT_EQ(slam.acceptedLoops().size(), 1u);

  // The run as a session folder, and back: the same trajectory, keyframes with their features, every landmark.
  const mapping::Session session = mapping::captureSession(slam.slam(), sequence.options().camera);
  EXPECT_EQ(session.frames.size(), sequence.size());
  const auto folder = scratchDir("session") / "run";
  mapping::saveSession(session, folder.string());
  const mapping::Session loaded = mapping::loadSession(folder.string());
  const Trajectory expected = slam.trajectory(), actual = loaded.trajectory();
  ASSERT_EQ(actual.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) EXPECT_TRUE(actual[i].pose.isApprox(expected[i].pose, 1e-9));
  ASSERT_EQ(loaded.keyframes.size(), session.keyframes.size());
  EXPECT_FALSE(loaded.keyframes[0].keypoints.empty());
  EXPECT_EQ(loaded.keyframes[0].descriptors.rows, static_cast<int>(loaded.keyframes[0].keypoints.size()));
  EXPECT_EQ(loaded.points.size(), slam.slam().map().mapPointCount());
  const auto graph = mapping::MiniMapGraph::fromSlamMap(slam.slam().map(), 3);
  EXPECT_EQ(graph.mergedMap().landmarks.size(), slam.slam().map().mapPointCount());
}

/// Runs the SLAM over the first `frames` frames; at frame `correct_at` (if given) the whole map is moved by
/// `offset` through a posted correction, as a loop closure would move it.
Trajectory runWithRigidCorrection(const simulation::SyntheticRgbdSequence& sequence, std::size_t frames,
                                  std::optional<std::size_t> correct_at) {
  frontend::RgbdSlamOptions options;
  options.backend.background_thread = false;
  frontend::RgbdSlam slam(sequence.options().camera, options);
  for (std::size_t i = 0; i < frames; ++i) {
    slam.process(sequence.frame(i).rgbd);
    if (correct_at && i == *correct_at) {
      frontend::PoseGraphCorrection correction;
      correction.base_corrections = slam.map().corrections();
      correction.delta_wc[0] = scriptedOffset();  // every keyframe follows keyframe 0
      EXPECT_TRUE(slam.map().postCorrection(correction));
    }
  }
  slam.finish();
  EXPECT_FALSE(slam.applyPendingCorrection()) << "applied by the frame after it was posted";
  return slam.trajectory();
}

TEST(LoopClosingSlam, TrackingFollowsACorrectionAsIfTheMapHadAlwaysBeenThere) {
  simulation::SyntheticRgbdOptions sequence_options;
  sequence_options.frames = 24;
  const simulation::SyntheticRgbdSequence sequence(sequence_options);
  const Trajectory plain = runWithRigidCorrection(sequence, sequence.size(), std::nullopt);
  const Trajectory corrected = runWithRigidCorrection(sequence, sequence.size(), 10);
  ASSERT_EQ(corrected.size(), plain.size());
  // Moving the whole map rigidly changes nothing but the frame: every pose, before and after the correction,
  // is the uncorrected one moved by the offset (last pose, motion model, last keyframe and local map followed).
  for (std::size_t i = 0; i < plain.size(); ++i) {
    const Eigen::Isometry3d expected = scriptedOffset() * plain[i].pose;
    EXPECT_LT((corrected[i].pose.translation() - expected.translation()).norm(), 1e-3) << "frame " << i;
    EXPECT_LT(Eigen::AngleAxisd(corrected[i].pose.linear().transpose() * expected.linear()).angle(), 1e-3)
        << "frame " << i;
  }
}

TEST(LoopClosingSlam, WithoutLoopClosureTheDetectorIsNeverCalled) {
  simulation::SyntheticRgbdOptions sequence_options;
  sequence_options.frames = 6;
  const simulation::SyntheticRgbdSequence sequence(sequence_options);
  mapping::LoopClosingSlamOptions options = inlineOptions();
  options.loop_closure = false;
  int calls = 0;
  mapping::LoopClosingSlam slam(
      sequence.options().camera,
      [&calls](const frontend::Map&, frontend::KeyframeId) -> std::optional<mapping::LoopConstraint> {
        ++calls;
        return std::nullopt;
      },
      options);
  for (std::size_t i = 0; i < sequence.size(); ++i) slam.process(sequence.frame(i).rgbd);
  slam.finish();
  EXPECT_EQ(calls, 0);
  EXPECT_EQ(slam.loopStats().loops_detected, 0u);
  EXPECT_EQ(slam.trajectory().size(), sequence.size());
  // With loop closure on, a detector is required.
  EXPECT_THROW(mapping::LoopClosingSlam(sequence.options().camera, {}, inlineOptions()), std::invalid_argument);
}

}  // namespace
}  // namespace weighted_icp::testing
