#pragma once
// Merging saved SLAM sessions: place recognition between their keyframes,
// verification with no odometry prior (their frames are unrelated), a relative
// transform only when several verified loops agree on it, then one pose graph
// over all merged keyframes, after a free-space check of the two maps in one
// frame (aliased places agree on a wrong transform; the rest of the maps then
// contradict each other). Sessions that do not overlap are reported, never
// forced together.
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "weighted_icp/core/trajectory.h"
#include "weighted_icp/mapping/binary_vocabulary.h"
#include "weighted_icp/mapping/free_space_check.h"
#include "weighted_icp/mapping/loop_verifier.h"
#include "weighted_icp/mapping/minimap_graph.h"
#include "weighted_icp/mapping/pose_graph.h"
#include "weighted_icp/mapping/session.h"
#include "weighted_icp/mapping/tracking_information.h"

namespace weighted_icp::mapping {

/// @brief Options of mergeSessions.
struct SessionMergeOptions {
  /// @brief Best-scoring keyframes of the other session verified per query keyframe.
  std::size_t candidates_per_keyframe = 3;
  /// @brief Verified loops that must agree on the relative transform (one could be an aliased place).
  std::size_t min_agreeing_loops = 2;
  /// @brief Two loops agree when their relative transforms differ by less than this (metres, degrees).
  double agreement_translation_m = 0.10, agreement_rotation_deg = 5.0;
  /// @brief Geometric verification (PnP from any starting pose, weighted ICP check).
  LoopVerificationOptions verification;
  /// @brief Once a session is linked (agreeing loops, free space), verify its other keyframes again with the link
  /// as prior, as loops within one session are: the relative pose the nearest agreeing loop predicts, within
  /// `link_drift` of the path travelled from that loop's keyframes in both sessions.
  bool loops_with_link_prior = true;
  /// @brief How far a loop verified with the link's prior may be from the pose it predicts.
  DriftBounds link_drift;
  /// @brief The two maps in one frame must not contradict each other: at most this fraction of the landmarks
  /// judged by checkFreeSpace (both ways) may lie, by the majority of their sightings, in space the other
  /// session's keyframes saw through. Chosen between correct merges (at most 0.22 % measured: synthetic, a larger
  /// room, TUM fr1 and fr3) and merges forced by perceptual aliasing (at least 4.1 %), about ten times above the
  /// first (docs/mapping.md). Judged with the agreed transform and, when that fails, on the two maps as a pose graph
  /// of both sessions' odometry and the agreeing loops lays them (a session that drifted within itself).
  double max_free_space_violation = 0.02;
  /// @brief How checkFreeSpace judges a sighting.
  FreeSpaceOptions free_space;
  /// @brief Odometry edges within a session take their information from tracking (the landmarks both keyframes
  /// observe, as a loop closure within one session does by default); false: the noise model for every edge.
  bool tracking_information = true;
  /// @brief How tracking's information is estimated.
  TrackingInformationOptions tracking;
  /// @brief Information of the odometry edges tracking does not hold (across a tracking loss, too few landmarks).
  OdometryNoiseModel odometry;
  /// @brief The joint pose graph's solver and gate.
  PoseGraphOptions pose_graph;
  /// @brief Keyframes per mini-map of the merged mini-map graph.
  std::size_t keyframes_per_minimap = 10;
  /// @brief Called after each query keyframe is verified (a merge of long sessions takes minutes): the pass
  /// ("session 1 against 0", or "... with the link as prior"), keyframes done and keyframes in the pass. Empty:
  /// silent. Called from the merging thread.
  std::function<void(const std::string& pass, std::size_t done, std::size_t total)> progress;
};

/// @brief How one session joined the merge.
struct SessionLink {
  /// @brief Whether it overlaps (and was merged); false: its frames are in no output.
  bool merged = false;
  /// @brief The merged session it was found to overlap (itself for the first session).
  std::size_t linked_to = 0;
  /// @brief Verified loops found against the already merged sessions, and those that agree on the transform.
  std::size_t loops_found = 0, loops_agreeing = 0;
  /// @brief Loops added once linked, verified with the link as prior (SessionMergeOptions::loops_with_link_prior).
  std::size_t loops_with_link_prior = 0;
  /// @brief The free-space check of the agreed transform against the session it was tested with (the one it
  /// joined, or the last one tried): landmarks judged both ways and the fraction in the other's free space.
  std::size_t free_space_judged = 0;
  double free_space_violation = 0.0;
  /// @brief The fraction with the agreed transform alone, and whether the check was made again on the maps as the
  /// two sessions' pose graph lays them (the rigid one failed); free_space_judged and free_space_violation are then
  /// the second judgement's.
  double free_space_rigid_violation = 0.0;
  bool free_space_optimised = false;
  /// @brief Its world frame in the first session's world frame, after the joint optimisation.
  Eigen::Isometry3d world_in_first = Eigen::Isometry3d::Identity();
};

/// @brief The result of a merge.
struct SessionMerge {
  /// @brief One per input session, in order (the first is the reference, always merged).
  std::vector<SessionLink> sessions;
  /// @brief The agreeing loops between sessions; keyframe ids are session * MiniMapGraph::kSessionIdStride + id.
  std::vector<LoopConstraint> loops;
  /// @brief Per loop: whether the joint pose graph's consistency test admitted it (PoseGraphSummary::edge_used).
  std::vector<bool> loop_used;
  /// @brief Every frame of every merged session in the first session's frame (original timestamps, session by
  /// session: runs of one sequence that overlap in time repeat timestamps).
  Trajectory trajectory;
  /// @brief The same frames per session (empty for a session not merged); each has unique timestamps.
  std::vector<Trajectory> session_trajectories;
  /// @brief The mini-maps of the merged sessions, sequential edges per session and merge edges between them.
  MiniMapGraph graph;
  /// @brief The joint pose graph's outcome.
  PoseGraphSummary summary;
};

/// @brief Merges sessions into the first one's frame.
/// @param sessions At least one (std::invalid_argument otherwise); each as loadSession returns it.
/// @param vocabulary Place-recognition vocabulary (not null).
/// @param options See SessionMergeOptions.
SessionMerge mergeSessions(const std::vector<Session>& sessions, const BinaryVocabulary::ConstPtr& vocabulary,
                           const SessionMergeOptions& options = {});

}  // namespace weighted_icp::mapping
