// Merging sessions: overlap by place recognition, verification without a prior, agreement, joint pose graph.
#include "weighted_icp/mapping/session_merger.h"

#include <cmath>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>

#include "weighted_icp/mapping/keyframe_snapshot.h"
#include "weighted_icp/mapping/place_recognizer.h"

namespace weighted_icp::mapping {

namespace {

constexpr std::uint64_t kStride = MiniMapGraph::kSessionIdStride;

/// A loaded session as the merge reads it: its keyframes' snapshot and their words.
struct Prepared {
  KeyframeSnapshot snapshot;
  std::map<frontend::KeyframeId, BowVector> bows;
};

Prepared prepare(const Session& session, const BinaryVocabulary& vocabulary) {
  Prepared prepared{KeyframeSnapshot::of(*session.toMap()), {}};
  for (const auto& [id, keyframe] : prepared.snapshot.keyframes)
    prepared.bows[id] = vocabulary.transform(keyframe.descriptors);
  return prepared;
}

/// Verified loops from `query`'s keyframes to `match`'s (query = query keyframe, match = match keyframe, local ids).
std::vector<LoopConstraint> verifiedLoops(const Prepared& query, const Prepared& match,
                                          const BinaryVocabulary::ConstPtr& vocabulary, const LoopVerifier& verifier,
                                          const SessionMergeOptions& options) {
  PlaceRecognitionOptions recognition;
  recognition.exclude_recent = 0;  // the other session's ids are unrelated to the query's
  PlaceRecognizer recognizer(vocabulary, recognition);
  for (const auto& [id, bow] : match.bows) recognizer.add(id, bow);
  std::vector<LoopConstraint> loops;
  for (const auto& [id, bow] : query.bows) {
    // An id no keyframe of `match` has, so that no candidate is excluded as "recent".
    const auto ranked = recognizer.rank(kStride + id, bow, {});
    for (std::size_t c = 0; c < ranked.size() && c < options.candidates_per_keyframe; ++c) {
      LoopVerification result = verifier.verify(query.snapshot, id, match.snapshot, ranked[c].keyframe, std::nullopt);
      if (!result.accepted) continue;
      result.constraint.score = ranked[c].score;
      loops.push_back(result.constraint);
      break;
    }
  }
  return loops;
}

/// The query session's world in the match session's world, as one loop says.
Eigen::Isometry3d worldTransform(const LoopConstraint& loop, const Prepared& query, const Prepared& match) {
  return match.snapshot.keyframes.at(loop.match).pose_wc * loop.query_in_match *
         query.snapshot.keyframes.at(loop.query).pose_wc.inverse();
}

bool agree(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, const SessionMergeOptions& options) {
  const Eigen::Isometry3d delta = a.inverse() * b;
  return delta.translation().norm() < options.agreement_translation_m &&
         Eigen::AngleAxisd(delta.rotation()).angle() * 180.0 / M_PI < options.agreement_rotation_deg;
}

/// The largest set of loops agreeing on one transform (ties: more inliers), and that transform.
std::vector<LoopConstraint> agreeingLoops(const std::vector<LoopConstraint>& loops, const Prepared& query,
                                          const Prepared& match, const SessionMergeOptions& options,
                                          Eigen::Isometry3d& transform) {
  std::vector<LoopConstraint> best;
  std::size_t best_inliers = 0;
  for (const LoopConstraint& seed : loops) {
    const Eigen::Isometry3d candidate = worldTransform(seed, query, match);
    std::vector<LoopConstraint> agreeing;
    std::size_t inliers = 0;
    for (const LoopConstraint& other : loops)
      if (agree(candidate, worldTransform(other, query, match), options)) {
        agreeing.push_back(other);
        inliers += other.inliers;
      }
    if (agreeing.size() > best.size() || (agreeing.size() == best.size() && inliers > best_inliers)) {
      best = agreeing;
      best_inliers = inliers;
      transform = candidate;
    }
  }
  return best;
}

/// The free-space check both ways (each map's landmarks against the other's keyframes), recorded in `link`; true
/// when the violations stay within the options' bound.
bool consistent(const Prepared& query, const PinholeCamera& query_camera, const Prepared& match,
                const PinholeCamera& match_camera, const Eigen::Isometry3d& query_in_match,
                const SessionMergeOptions& options, SessionLink& link) {
  const FreeSpaceCheck into_match =
      checkFreeSpace(match.snapshot, match_camera, query.snapshot, query_in_match, options.free_space);
  const FreeSpaceCheck into_query =
      checkFreeSpace(query.snapshot, query_camera, match.snapshot, query_in_match.inverse(), options.free_space);
  FreeSpaceCheck both = into_match;
  both += into_query;
  link.free_space_judged = both.landmarks_judged;
  link.free_space_violation = both.violationRatio();
  return both.violationRatio() <= options.max_free_space_violation;
}

/// Links every session it can to the merged ones (the first, then those linked to it), until none is left.
void linkSessions(const std::vector<Prepared>& prepared, const BinaryVocabulary::ConstPtr& vocabulary,
                  const SessionMergeOptions& options, const std::vector<Session>& sessions, SessionMerge& merge) {
  merge.sessions[0].merged = true;
  for (bool progress = true; progress;) {
    progress = false;
    for (std::size_t s = 1; s < prepared.size(); ++s) {
      SessionLink& link = merge.sessions[s];
      const LoopVerifier verifier(sessions[s].camera, options.verification);  // PnP of the query's pixels
      for (std::size_t m = 0; m < prepared.size() && !link.merged; ++m) {
        if (m == s || !merge.sessions[m].merged) continue;
        const auto loops = verifiedLoops(prepared[s], prepared[m], vocabulary, verifier, options);
        Eigen::Isometry3d s_in_m = Eigen::Isometry3d::Identity();
        const auto agreeing = agreeingLoops(loops, prepared[s], prepared[m], options, s_in_m);
        link.loops_found += loops.size();
        link.loops_agreeing = std::max(link.loops_agreeing, agreeing.size());
        if (agreeing.size() < options.min_agreeing_loops) continue;
        if (!consistent(prepared[s], sessions[s].camera, prepared[m], sessions[m].camera, s_in_m, options, link))
          continue;
        link.merged = progress = true;
        link.linked_to = m;
        link.world_in_first = merge.sessions[m].world_in_first * s_in_m;
        for (LoopConstraint loop : agreeing) {
          loop.query += s * kStride;
          loop.match += m * kStride;
          merge.loops.push_back(loop);
        }
      }
    }
  }
}

/// One pose graph over all merged keyframes (odometry within sessions, the agreeing loops between them);
/// returns the optimised poses by offset id.
std::map<frontend::KeyframeId, Eigen::Isometry3d> optimise(const std::vector<Prepared>& prepared,
                                                           const SessionMergeOptions& options, SessionMerge& merge) {
  PoseGraph graph;
  bool first = true;
  for (std::size_t s = 0; s < prepared.size(); ++s) {
    if (!merge.sessions[s].merged) continue;
    const frontend::Keyframe* previous = nullptr;
    for (const auto& [id, keyframe] : prepared[s].snapshot.keyframes) {
      graph.addNode(s * kStride + id, merge.sessions[s].world_in_first * keyframe.pose_wc, first);
      first = false;
      if (previous) {
        const Eigen::Isometry3d relative = previous->pose_wc.inverse() * keyframe.pose_wc;
        graph.addEdge({s * kStride + previous->id, s * kStride + id, relative,
                       odometryInformation(relative, options.odometry, previous->segment != keyframe.segment),
                       PoseGraphEdgeKind::Odometry});
      }
      previous = &keyframe;
    }
  }
  for (const LoopConstraint& loop : merge.loops) graph.addEdge(loopEdge(loop));
  merge.summary = graph.optimize(options.pose_graph);
  if (!merge.summary.ok) throw std::runtime_error("joint pose graph failed: " + merge.summary.message);
  return graph.poses();
}

/// The session moved to the optimised poses: each keyframe to its own, each landmark with its first observer.
Session corrected(const Session& session, std::size_t s,
                  const std::map<frontend::KeyframeId, Eigen::Isometry3d>& poses) {
  Session moved = session;
  std::map<frontend::KeyframeId, Eigen::Isometry3d> delta;
  for (auto& keyframe : moved.keyframes) {
    const Eigen::Isometry3d& pose = poses.at(s * kStride + keyframe.id);
    delta[keyframe.id] = pose * keyframe.pose_wc.inverse();
    keyframe.pose_wc = pose;
  }
  for (auto& point : moved.points)
    if (!point.observations.empty()) {
      const Eigen::Matrix3d rotation = delta.at(point.observations.front().keyframe).rotation();
      point.position = delta.at(point.observations.front().keyframe) * point.position;
      point.covariance = rotation * point.covariance * rotation.transpose();
    }
  return moved;
}

/// Adds `part`'s nodes and edges to `graph`; returns the offset of its node ids.
std::size_t append(MiniMapGraph& graph, const MiniMapGraph& part) {
  const std::size_t offset = graph.nodes().size();
  for (const MiniMapNode& node : part.nodes()) graph.addNode(node);
  for (MiniMapEdge edge : part.edges()) {
    edge.from += offset;
    edge.to += offset;
    graph.addEdge(edge);
  }
  return offset;
}

/// The mini-map holding an (offset) keyframe id.
std::optional<MiniMapId> minimapOf(const MiniMapGraph& graph, frontend::KeyframeId offset_id) {
  for (const MiniMapNode& node : graph.nodes())
    if (node.session == offset_id / kStride && node.landmarks.frames.count(offset_id % kStride)) return node.id;
  return std::nullopt;
}

void buildGraphAndTrajectory(const std::vector<Session>& sessions, const SessionMergeOptions& options,
                             const std::map<frontend::KeyframeId, Eigen::Isometry3d>& poses, SessionMerge& merge) {
  for (std::size_t s = 0; s < sessions.size(); ++s) {
    if (!merge.sessions[s].merged) continue;
    const Session moved = corrected(sessions[s], s, poses);
    merge.session_trajectories[s] = moved.trajectory();
    for (const auto& frame : merge.session_trajectories[s]) merge.trajectory.push_back(frame);
    append(merge.graph, MiniMapGraph::fromSlamMap(*moved.toMap(), options.keyframes_per_minimap, s, options.odometry));
    // The first keyframe's pose after and before: the session's world in the first one's, optimised.
    const frontend::Keyframe& first = sessions[s].keyframes.front();
    merge.sessions[s].world_in_first = poses.at(s * kStride + first.id) * first.pose_wc.inverse();
  }
  for (const LoopConstraint& loop : merge.loops) {
    const auto from = minimapOf(merge.graph, loop.match), to = minimapOf(merge.graph, loop.query);
    if (!from || !to) continue;
    MiniMapEdge edge;
    edge.from = *from;
    edge.to = *to;
    edge.kind = MiniMapEdgeKind::Merge;
    edge.to_in_from = merge.graph.nodes()[*from].anchor_wc.inverse() * merge.graph.nodes()[*to].anchor_wc;
    edge.strategy = "bow+pnp+weighted_icp";
    edge.fitness = loop.fitness;
    edge.covariance = (0.5 * (loop.information + loop.information.transpose())).inverse();
    merge.graph.addEdge(edge);
  }
}

}  // namespace

SessionMerge mergeSessions(const std::vector<Session>& sessions, const BinaryVocabulary::ConstPtr& vocabulary,
                           const SessionMergeOptions& options) {
  if (sessions.empty()) throw std::invalid_argument("mergeSessions: no session");
  if (!vocabulary) throw std::invalid_argument("mergeSessions: no vocabulary");
  std::vector<Prepared> prepared;
  for (const Session& session : sessions) {
    if (session.keyframes.empty()) throw std::invalid_argument("mergeSessions: a session has no keyframe");
    prepared.push_back(prepare(session, *vocabulary));
  }
  SessionMerge merge;
  merge.sessions.resize(sessions.size());
  merge.session_trajectories.resize(sessions.size());
  linkSessions(prepared, vocabulary, options, sessions, merge);
  const auto poses = optimise(prepared, options, merge);
  buildGraphAndTrajectory(sessions, options, poses, merge);
  return merge;
}

}  // namespace weighted_icp::mapping
