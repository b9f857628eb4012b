// The loop detector (place recognition + verification) inside LoopClosingSlam on whole synthetic runs: a sequence
// that comes back to its start closes a loop and its ATE does not get worse; one that never revisits closes none.
#include <algorithm>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "mapping_fixtures.h"
#include "weighted_icp/mapping/loop_closing_slam.h"
#include "weighted_icp/mapping/loop_detector.h"
#include "weighted_icp/mapping/loop_verifier.h"
#include "weighted_icp/metrics/trajectory_error.h"
#include "weighted_icp/simulation/rgbd_sequence.h"

namespace weighted_icp::testing {
namespace {

struct SlamRun {
  mapping::LoopClosingStats stats;
  double ate_m = 0.0;
  mapping::LoopDetectorStats detector;
  std::vector<mapping::LoopCandidateRecord> candidates;
};

/// Runs LoopClosingSlam inline (reproducible) over the whole sequence, with or without loop closure; the frames in
/// `blackout` come black and without depth (a covered lens), so tracking is lost there.
SlamRun runSlam(const simulation::SyntheticRgbdSequence& sequence, bool loop_closure,
                const mapping::LoopDetectorOptions& detector_options = {}, const std::set<std::size_t>& blackout = {}) {
  mapping::LoopClosingSlamOptions options;
  options.slam.backend.background_thread = false;
  options.loop_closing.background_thread = false;
  options.loop_closure = loop_closure;
  const auto detector =
      std::make_shared<mapping::BowLoopDetector>(trainedVocabulary(), sequence.options().camera, detector_options);
  mapping::LoopClosingSlam slam(sequence.options().camera, mapping::asLoopDetector(detector), options);
  for (std::size_t i = 0; i < sequence.size(); ++i) {
    RgbdFrame frame = sequence.frame(i).rgbd;
    if (blackout.count(i)) {
      frame.color.setTo(cv::Scalar::all(0));
      frame.depth.setTo(0.0f);
    }
    slam.process(frame);
  }
  slam.finish();
  Trajectory truth;
  for (std::size_t i = 0; i < sequence.size(); ++i) truth.push_back({sequence.timestamp(i), sequence.cameraToWorld(i)});
  return {slam.loopStats(), metrics::computeAte(truth, slam.trajectory()).translation.rmse, detector->stats(),
          detector->candidates()};
}

TEST(LoopDetector, ClosesTheLoopOfARevisitingSequenceWithoutMakingItWorse) {
  simulation::SyntheticRgbdOptions options;
  options.seed = 7;  // not the vocabulary's training seed
  options.frames = 228;
  options.frames_per_loop = 180.0;
  const simulation::SyntheticRgbdSequence sequence(options);
  const SlamRun with = runSlam(sequence, true);
  const SlamRun without = runSlam(sequence, false);
  EXPECT_GE(with.stats.loops_detected, with.stats.loops_accepted);
  EXPECT_GE(with.stats.loops_accepted, 1u);
  EXPECT_GE(with.stats.pose_graph_optimisations, 1u);
  EXPECT_EQ(without.stats.loops_detected, 0u);
  // Every candidate is on record with its verdict; the verified ones are the loops handed to the pose graph.
  EXPECT_EQ(with.candidates.size(), with.detector.candidates);
  const auto verified = std::count_if(with.candidates.begin(), with.candidates.end(),
                                      [](const mapping::LoopCandidateRecord& c) { return c.refused_by.empty(); });
  EXPECT_EQ(static_cast<std::size_t>(verified), with.stats.loops_detected);
  EXPECT_EQ(with.detector.verified, with.stats.loops_detected);
  EXPECT_GE(with.detector.queries, with.detector.verified);
  const std::set<std::string> checks = {
      "descriptor_matches", "pnp",     "pnp_inliers", "icp_landmarks", "icp_degenerate", "icp_correction",
      "icp_inliers",        "overlap", "fitness",     "drift",         "culled"};
  const std::size_t mini_map = mapping::LoopVerificationOptions{}.neighbour_keyframes;
  for (const mapping::LoopCandidateRecord& c : with.candidates) {
    EXPECT_LT(c.match, c.query);
    if (c.refused_by.empty()) {
      // The loop joins its candidate or the keyframe of the candidate's mini-map that saw the most PnP inliers.
      EXPECT_LE(c.edge_match > c.match ? c.edge_match - c.match : c.match - c.edge_match, mini_map);
      EXPECT_LT(c.edge_match, c.query);
      continue;
    }
    EXPECT_EQ(c.edge_match, c.match) << "a refused candidate joins nothing";
    EXPECT_TRUE(checks.count(c.refused_by)) << c.refused_by;
    EXPECT_FALSE(c.reason.empty()) << c.refused_by;
  }
  // Not worse, up to a millimetre (the clean sequence's odometry drifts little).
  EXPECT_LE(with.ate_m, without.ate_m + 1e-3) << "with " << with.ate_m << " m, without " << without.ate_m << " m";
}

TEST(LoopDetector, AcceptsNoLoopOnASequenceThatNeverRevisits) {
  simulation::SyntheticRgbdOptions options;
  options.seed = 8;
  options.frames = 150;  // a fifth of the default 800-frame round: never back at a place seen before
  const simulation::SyntheticRgbdSequence sequence(options);
  EXPECT_EQ(runSlam(sequence, true).stats.loops_accepted, 0u);
}

TEST(LoopDetector, BridgesATrackingLossToThePlaceSeenJustBefore) {
  // Ten frames without image or depth: tracking is lost, and the new segment starts at the last known pose while
  // the camera moved on. Its first keyframe is verified against the previous segment's last one, and the loop edge
  // puts the segment back; without the bridge (place recognition alone) nothing links the two.
  simulation::SyntheticRgbdOptions options;
  options.seed = 9;
  options.frames = 90;
  options.frames_per_loop = 240.0;
  const simulation::SyntheticRgbdSequence sequence(options);
  std::set<std::size_t> blackout;
  for (std::size_t i = 40; i < 50; ++i) blackout.insert(i);
  mapping::LoopDetectorOptions without_bridge;
  without_bridge.bridge_keyframes = 0;
  const SlamRun bridged = runSlam(sequence, true, {}, blackout);
  const SlamRun unbridged = runSlam(sequence, true, without_bridge, blackout);
  const auto is_bridge = [](const mapping::LoopCandidateRecord& c) { return c.reason.rfind("segment bridge", 0) == 0; };
  ASSERT_TRUE(std::any_of(bridged.candidates.begin(), bridged.candidates.end(), [&](const auto& c) {
    return is_bridge(c) && c.refused_by.empty();
  })) << "no bridge verified";
  EXPECT_GE(bridged.stats.loops_accepted, 1u);
  EXPECT_TRUE(std::none_of(unbridged.candidates.begin(), unbridged.candidates.end(), is_bridge));
  EXPECT_LT(bridged.ate_m, 0.5 * unbridged.ate_m) << "bridged " << bridged.ate_m << " m, not " << unbridged.ate_m;
}

TEST(LoopDetector, RefusesToBeBuiltWithoutAVocabularyOrWrapped) {
  const PinholeCamera camera = simulation::SyntheticRgbdOptions{}.camera;
  EXPECT_THROW(mapping::BowLoopDetector(nullptr, camera), std::invalid_argument);
  EXPECT_THROW(mapping::asLoopDetector(nullptr), std::invalid_argument);
}

}  // namespace
}  // namespace weighted_icp::testing
