// Merging sessions: overlap by place recognition, verification without a prior, agreement, joint pose graph.
#include "weighted_icp/mapping/session_merger.h"

#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>

#include "weighted_icp/mapping/keyframe_snapshot.h"
#include "weighted_icp/mapping/place_recognizer.h"
#include "weighted_icp/mapping/tracking_information.h"

namespace weighted_icp::mapping {

namespace {

constexpr std::uint64_t kStride = MiniMapGraph::kSessionIdStride;

/// A loaded session as the merge reads it: its keyframes' snapshot and their words.
struct Prepared {
  KeyframeSnapshot snapshot;
  std::map<frontend::KeyframeId, BowVector> bows;
  /// Distance travelled from the first keyframe to each (KeyframeSnapshot::pathLength from the first, all at once):
  /// the path between two keyframes is the difference, which the link's prior asks for per candidate and loop.
  std::map<frontend::KeyframeId, double> travelled;
};

Prepared prepare(const Session& session, const BinaryVocabulary& vocabulary) {
  Prepared prepared{KeyframeSnapshot::of(*session.toMap()), {}, {}};
  const frontend::Keyframe* previous = nullptr;
  double travelled = 0.0;
  for (const auto& [id, keyframe] : prepared.snapshot.keyframes) {
    prepared.bows[id] = vocabulary.transform(keyframe.descriptors);
    if (previous) travelled += (keyframe.pose_wc.translation() - previous->pose_wc.translation()).norm();
    prepared.travelled[id] = travelled;
    previous = &keyframe;
  }
  return prepared;
}

/// Gives the prior of a candidate (query keyframe, match keyframe), or none.
using PriorOf = std::function<std::optional<LoopPrior>(frontend::KeyframeId, frontend::KeyframeId)>;

/// For each of `query`'s keyframes, `match`'s keyframes ranked by place recognition, best first (at most
/// `candidates_per_keyframe`). Computed once per pair of sessions: both verification passes read it.
using Rankings = std::map<frontend::KeyframeId, std::vector<PlaceCandidate>>;

Rankings rankAgainst(const Prepared& query, const Prepared& match, const BinaryVocabulary::ConstPtr& vocabulary,
                     const SessionMergeOptions& options) {
  PlaceRecognitionOptions recognition;
  recognition.exclude_recent = 0;  // the other session's ids are unrelated to the query's
  PlaceRecognizer recognizer(vocabulary, recognition);
  for (const auto& [id, bow] : match.bows) recognizer.add(id, bow);
  Rankings rankings;
  for (const auto& [id, bow] : query.bows) {
    // An id no keyframe of `match` has, so that no candidate is excluded as "recent".
    std::vector<PlaceCandidate> ranked = recognizer.rank(kStride + id, bow, {});
    if (ranked.size() > options.candidates_per_keyframe) ranked.resize(options.candidates_per_keyframe);
    rankings.emplace(id, std::move(ranked));
  }
  return rankings;
}

/// Verified loops from `query`'s keyframes to `match`'s (query = query keyframe, match = match keyframe, local ids),
/// at most one per query keyframe, its candidates tried in `rankings`' order; the keyframes in `skip` are not queried.
std::vector<LoopConstraint> verifiedLoops(const Prepared& query, const Prepared& match, const Rankings& rankings,
                                          const LoopVerifier& verifier, const SessionMergeOptions& options,
                                          const PriorOf& prior_of, const std::string& pass,
                                          const std::set<frontend::KeyframeId>& skip = {}) {
  std::vector<LoopConstraint> loops;
  const std::size_t total = rankings.size() - skip.size();
  std::size_t done = 0;
  for (const auto& [id, ranked] : rankings) {
    if (skip.count(id)) continue;
    if (options.progress) options.progress(pass, done++, total);
    for (const PlaceCandidate& candidate : ranked) {
      LoopVerification result =
          verifier.verify(query.snapshot, id, match.snapshot, candidate.keyframe, prior_of(id, candidate.keyframe));
      if (!result.accepted) continue;
      result.constraint.score = candidate.score;
      loops.push_back(result.constraint);
      break;
    }
  }
  if (options.progress) options.progress(pass, total, total);
  return loops;
}

/// Moves `keyframe` to its optimised pose (its id offset by s * kStride in `poses`); returns how it moved (the new pose
/// times the old one's inverse), for its landmarks to follow.
Eigen::Isometry3d moveToOptimised(frontend::Keyframe& keyframe, std::size_t s,
                                  const std::map<frontend::KeyframeId, Eigen::Isometry3d>& poses) {
  const Eigen::Isometry3d& pose = poses.at(s * kStride + keyframe.id);
  const Eigen::Isometry3d moved = pose * keyframe.pose_wc.inverse();
  keyframe.pose_wc = pose;
  return moved;
}

/// A landmark moved as its first observer moved (`delta`: each keyframe's new pose times its old one's inverse).
void moveWithFirstObserver(frontend::MapPoint& point, const std::map<frontend::KeyframeId, Eigen::Isometry3d>& delta) {
  if (point.observations.empty()) return;
  const Eigen::Isometry3d& moved = delta.at(point.observations.front().keyframe);
  point.position = moved * point.position;
  point.covariance = moved.rotation() * point.covariance * moved.rotation().transpose();
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

/// The prior a link gives a candidate once two sessions are linked: the relative pose predicted by the agreeing
/// loop nearest to it (path travelled in both sessions from that loop's keyframes), with bounds growing with that
/// path as within one session (odometryPrior).
LoopPrior linkPrior(const Prepared& query, frontend::KeyframeId q, const Prepared& match, frontend::KeyframeId c,
                    const std::vector<LoopConstraint>& agreeing, const DriftBounds& bounds) {
  double nearest_path = std::numeric_limits<double>::infinity();
  const LoopConstraint* nearest = &agreeing.front();
  for (const LoopConstraint& loop : agreeing) {
    const double path = std::abs(query.travelled.at(q) - query.travelled.at(loop.query)) +
                        std::abs(match.travelled.at(c) - match.travelled.at(loop.match));
    if (path < nearest_path) {
      nearest_path = path;
      nearest = &loop;
    }
  }
  LoopPrior prior;
  prior.expected_query_in_match = match.snapshot.keyframes.at(c).pose_wc.inverse() *
                                  worldTransform(*nearest, query, match) * query.snapshot.keyframes.at(q).pose_wc;
  prior.max_translation_m = bounds.translation_floor_m + bounds.translation_per_metre * nearest_path;
  prior.max_rotation_deg = bounds.rotation_floor_deg + bounds.rotation_per_metre_deg * nearest_path;
  return prior;
}

/// Per odometry edge of a session (entry i: its keyframes i-1 -> i in id order; entry 0 empty), the relative pose's
/// covariance from tracking where the landmarks hold it; all empty when the options use the noise model only.
std::vector<std::optional<Covariance6d>> trackingCovariances(const Prepared& session, const PinholeCamera& camera,
                                                             const SessionMergeOptions& options) {
  if (!options.tracking_information) return {};
  std::vector<frontend::KeyframeId> ids;
  for (const auto& entry : session.snapshot.keyframes) ids.push_back(entry.first);
  return odometryEdgeCovariances(session.snapshot, ids, camera, options.tracking);
}

/// The free-space check both ways (each map's landmarks against the other's keyframes), recorded in `link`; true
/// when the violations stay within the options' bound.
bool consistent(const KeyframeSnapshot& query, const PinholeCamera& query_camera, const KeyframeSnapshot& match,
                const PinholeCamera& match_camera, const Eigen::Isometry3d& query_in_match,
                const SessionMergeOptions& options, SessionLink& link) {
  const FreeSpaceCheck into_match = checkFreeSpace(match, match_camera, query, query_in_match, options.free_space);
  const FreeSpaceCheck into_query =
      checkFreeSpace(query, query_camera, match, query_in_match.inverse(), options.free_space);
  FreeSpaceCheck both = into_match;
  both += into_query;
  link.free_space_judged = both.landmarks_judged;
  link.free_space_violation = both.violationRatio();
  return both.violationRatio() <= options.max_free_space_violation;
}

/// Adds session `s`'s keyframes (ids offset by s * kStride, poses moved by `world`) and its odometry edges to
/// `graph`; the first keyframe held fixed when `fix_first`.
void addSession(PoseGraph& graph, const Prepared& session, const PinholeCamera& camera, std::size_t s,
                const Eigen::Isometry3d& world, bool fix_first, const SessionMergeOptions& options) {
  const auto covariances = trackingCovariances(session, camera, options);
  const frontend::Keyframe* previous = nullptr;
  std::size_t i = 0;
  for (const auto& [id, keyframe] : session.snapshot.keyframes) {
    graph.addNode(s * kStride + id, world * keyframe.pose_wc, fix_first && !previous);
    if (previous) {
      const Eigen::Isometry3d relative = previous->pose_wc.inverse() * keyframe.pose_wc;
      const bool across_segments = previous->segment != keyframe.segment;
      const bool tracked = !across_segments && i < covariances.size() && covariances[i];
      graph.addEdge({s * kStride + previous->id, s * kStride + id, relative,
                     tracked ? relativeOdometryInformation(*covariances[i], options.tracking)
                             : odometryInformation(relative, options.odometry, across_segments),
                     PoseGraphEdgeKind::Odometry});
    }
    previous = &keyframe;
    ++i;
  }
}

/// The map moved to optimised poses (ids offset by s * kStride): each keyframe to its own, each landmark with its
/// first observer.
KeyframeSnapshot movedSnapshot(const KeyframeSnapshot& snapshot, std::size_t s,
                               const std::map<frontend::KeyframeId, Eigen::Isometry3d>& poses) {
  KeyframeSnapshot moved = snapshot;
  std::map<frontend::KeyframeId, Eigen::Isometry3d> delta;
  for (auto& [id, keyframe] : moved.keyframes) delta[id] = moveToOptimised(keyframe, s, poses);
  for (auto& [id, point] : moved.points) moveWithFirstObserver(point, delta);
  return moved;
}

/// The free-space check on the two maps as the joint pose graph lays them: both sessions' odometry and the agreeing
/// loops optimised, each map moved to its optimised poses. A session that drifted within itself cannot lie rigidly
/// on the other everywhere, however right the link (fr3 there and back, Kinect-like and dark: its way back 6 cm off
/// on its own, five agreeing loops, 3.1-17 % of the landmarks in free space laid by any one loop's transform).
bool consistentOnceOptimised(const Prepared& query, const PinholeCamera& query_camera, std::size_t s,
                             const Prepared& match, const PinholeCamera& match_camera, std::size_t m,
                             const Eigen::Isometry3d& query_in_match, const std::vector<LoopConstraint>& agreeing,
                             const SessionMergeOptions& options, SessionLink& link) {
  PoseGraph graph;
  addSession(graph, match, match_camera, m, Eigen::Isometry3d::Identity(), true, options);
  addSession(graph, query, query_camera, s, query_in_match, false, options);
  for (LoopConstraint loop : agreeing) {
    loop.query += s * kStride;
    loop.match += m * kStride;
    graph.addEdge(loopEdge(loop));
  }
  if (!graph.optimize(options.pose_graph).ok) return false;
  return consistent(movedSnapshot(query.snapshot, s, graph.poses()), query_camera,
                    movedSnapshot(match.snapshot, m, graph.poses()), match_camera, Eigen::Isometry3d::Identity(),
                    options, link);
}

/// Once two sessions are linked they are verified again like one session: each query keyframe no agreeing loop
/// holds, with the link's prior (linkPrior), so that the plain-ICP check of a loop within a session applies and
/// loops far from the first ones bring the drift between them to the pose graph. Without a prior, the sparse
/// clouds of a larger room made the weighted check refuse most true loops (LoopVerifier::verify).
std::vector<LoopConstraint> loopsWithLinkPrior(const Prepared& query, const Prepared& match, const Rankings& rankings,
                                               const std::vector<LoopConstraint>& agreeing,
                                               const LoopVerifier& verifier, const SessionMergeOptions& options,
                                               const std::string& pass) {
  std::set<frontend::KeyframeId> linked;
  for (const LoopConstraint& loop : agreeing) linked.insert(loop.query);
  return verifiedLoops(
      query, match, rankings, verifier, options,
      [&](frontend::KeyframeId q, frontend::KeyframeId c) {
        return std::optional<LoopPrior>(linkPrior(query, q, match, c, agreeing, options.link_drift));
      },
      pass, linked);
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
        const std::string pass = "session " + std::to_string(s) + " against " + std::to_string(m);
        const Rankings rankings = rankAgainst(prepared[s], prepared[m], vocabulary, options);
        const auto loops = verifiedLoops(
            prepared[s], prepared[m], rankings, verifier, options,
            [](frontend::KeyframeId, frontend::KeyframeId) { return std::nullopt; }, pass);
        Eigen::Isometry3d s_in_m = Eigen::Isometry3d::Identity();
        const auto agreeing = agreeingLoops(loops, prepared[s], prepared[m], options, s_in_m);
        link.loops_found += loops.size();
        link.loops_agreeing = std::max(link.loops_agreeing, agreeing.size());
        if (agreeing.size() < options.min_agreeing_loops) continue;
        // Rigidly first (as calibrated, docs/mapping.md), then as the joint pose graph would lay the two maps.
        const bool rigid = consistent(prepared[s].snapshot, sessions[s].camera, prepared[m].snapshot,
                                      sessions[m].camera, s_in_m, options, link);
        link.free_space_rigid_violation = link.free_space_violation;
        link.free_space_optimised = !rigid;
        if (!rigid && !consistentOnceOptimised(prepared[s], sessions[s].camera, s, prepared[m], sessions[m].camera, m,
                                               s_in_m, agreeing, options, link))
          continue;
        link.merged = progress = true;
        link.linked_to = m;
        link.world_in_first = merge.sessions[m].world_in_first * s_in_m;
        std::vector<LoopConstraint> joined = agreeing;
        if (options.loops_with_link_prior) {
          const auto added = loopsWithLinkPrior(prepared[s], prepared[m], rankings, agreeing, verifier, options,
                                                pass + " with the link as prior");
          link.loops_with_link_prior = added.size();
          joined.insert(joined.end(), added.begin(), added.end());
        }
        for (LoopConstraint loop : joined) {
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
                                                           const std::vector<Session>& sessions,
                                                           const SessionMergeOptions& options, SessionMerge& merge) {
  PoseGraph graph;
  bool first = true;
  for (std::size_t s = 0; s < prepared.size(); ++s) {
    if (!merge.sessions[s].merged) continue;
    addSession(graph, prepared[s], sessions[s].camera, s, merge.sessions[s].world_in_first, first, options);
    first = false;
  }
  const std::size_t first_loop_edge = graph.edges().size();
  for (const LoopConstraint& loop : merge.loops) graph.addEdge(loopEdge(loop));
  merge.summary = graph.optimize(options.pose_graph);
  if (!merge.summary.ok) throw std::runtime_error("joint pose graph failed: " + merge.summary.message);
  merge.loop_used.clear();
  for (std::size_t i = 0; i < merge.loops.size(); ++i)
    merge.loop_used.push_back(merge.summary.edge_used[first_loop_edge + i]);
  return graph.poses();
}

/// The session moved to the optimised poses: each keyframe to its own, each landmark with its first observer.
Session corrected(const Session& session, std::size_t s,
                  const std::map<frontend::KeyframeId, Eigen::Isometry3d>& poses) {
  Session moved = session;
  std::map<frontend::KeyframeId, Eigen::Isometry3d> delta;
  for (auto& keyframe : moved.keyframes) delta[keyframe.id] = moveToOptimised(keyframe, s, poses);
  for (auto& point : moved.points) moveWithFirstObserver(point, delta);
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
  const auto poses = optimise(prepared, sessions, options, merge);
  buildGraphAndTrajectory(sessions, options, poses, merge);
  return merge;
}

}  // namespace weighted_icp::mapping
