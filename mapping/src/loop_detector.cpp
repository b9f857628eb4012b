// Place recognition + geometric verification as the loop closer's detector.
#include "weighted_icp/mapping/loop_detector.h"

#include <set>
#include <stdexcept>
#include <string>
#include <utility>

#include "weighted_icp/mapping/keyframe_snapshot.h"

namespace weighted_icp::mapping {

namespace {
BinaryVocabulary::ConstPtr required(BinaryVocabulary::ConstPtr vocabulary) {
  if (!vocabulary) throw std::invalid_argument("BowLoopDetector: no vocabulary");
  return vocabulary;
}
LoopVerificationOptions withoutIcp(LoopVerificationOptions options) {
  options.icp_check = false;
  return options;
}
}  // namespace

BowLoopDetector::BowLoopDetector(BinaryVocabulary::ConstPtr vocabulary, const PinholeCamera& camera,
                                 LoopDetectorOptions options)
    : vocabulary_(required(std::move(vocabulary))),
      recognizer_(vocabulary_, options.recognition),
      verifier_(camera, options.verification),
      bridge_verifier_(camera, withoutIcp(options.verification)),
      options_(std::move(options)) {}

std::optional<LoopConstraint> BowLoopDetector::detect(const frontend::Map& map, frontend::KeyframeId query) {
  ++queries_;
  const KeyframeSnapshot snapshot = KeyframeSnapshot::of(map);
  const auto keyframe = snapshot.keyframes.find(query);
  // Bundle adjustment may have culled it since insertion: nothing to query, nothing to add.
  if (keyframe == snapshot.keyframes.end()) return std::nullopt;
  BowVector bow = vocabulary_->transform(keyframe->second.descriptors);
  const std::size_t segment = keyframe->second.segment;
  if (const auto previous = bridgeCandidate(snapshot, query)) {
    // No prior: the segment started at a guess (the last known pose), which is what the bridge corrects.
    LoopVerification result = bridge_verifier_.verify(snapshot, query, snapshot, *previous);
    candidates_.push_back({query, *previous, 0.0, result.refused_by, "segment bridge: " + result.reason,
                           result.accepted ? result.constraint.match : *previous});
    if (result.accepted) {
      bridged_segments_.insert(segment);
      recognizer_.add(query, std::move(bow), segment);
      return result.constraint;
    }
  }
  std::optional<LoopConstraint> loop;
  // Candidates come best first; the first verified one is the loop.
  for (const PlaceCandidate& candidate : recognizer_.detect(query, bow, snapshot.covisible(query), segment)) {
    if (!snapshot.keyframes.count(candidate.keyframe)) {
      candidates_.push_back({query, candidate.keyframe, candidate.normalised_score, "culled",
                             "bundle adjustment culled the keyframe since it was added", candidate.keyframe});
      continue;
    }
    std::optional<LoopPrior> prior;
    if (options_.use_odometry_prior) prior = odometryPrior(snapshot, query, candidate.keyframe, options_.drift);
    LoopVerification result = verifier_.verify(snapshot, query, snapshot, candidate.keyframe, prior);
    candidates_.push_back({query, candidate.keyframe, candidate.normalised_score, result.refused_by, result.reason,
                           result.accepted ? result.constraint.match : candidate.keyframe});
    if (!result.accepted) continue;
    result.constraint.score = candidate.normalised_score;
    loop = result.constraint;
    break;
  }
  recognizer_.add(query, std::move(bow), segment);
  return loop;
}

std::optional<frontend::KeyframeId> BowLoopDetector::bridgeCandidate(const KeyframeSnapshot& snapshot,
                                                                     frontend::KeyframeId query) const {
  const std::size_t segment = snapshot.keyframes.at(query).segment;
  if (segment == 0 || bridged_segments_.count(segment) || options_.bridge_keyframes == 0) return std::nullopt;
  std::size_t earlier_in_segment = 0;
  std::optional<frontend::KeyframeId> previous;
  for (const auto& [id, keyframe] : snapshot.keyframes) {
    if (id >= query) break;
    if (keyframe.segment == segment)
      ++earlier_in_segment;
    else
      previous = id;  // ids grow with time: the last one of an earlier segment
  }
  if (!previous || earlier_in_segment >= options_.bridge_keyframes) return std::nullopt;
  return previous;
}

LoopDetectorStats BowLoopDetector::stats() const {
  LoopDetectorStats stats;
  stats.queries = queries_;
  stats.candidates = candidates_.size();
  for (const LoopCandidateRecord& record : candidates_) stats.verified += record.refused_by.empty() ? 1 : 0;
  return stats;
}

std::vector<LoopCandidateVerdict> candidateVerdicts(const std::vector<LoopCandidateRecord>& candidates,
                                                    const std::vector<LoopConstraint>& accepted) {
  // An admitted loop names the keyframe its edge joins, which a verified candidate records as edge_match.
  std::set<std::pair<frontend::KeyframeId, frontend::KeyframeId>> admitted;
  for (const LoopConstraint& loop : accepted) admitted.emplace(loop.query, loop.match);
  std::vector<LoopCandidateVerdict> verdicts;
  for (const LoopCandidateRecord& c : candidates) {
    LoopCandidateVerdict v{c, c.refused_by, c.reason};
    if (v.verdict.empty() && admitted.count({c.query, c.edge_match})) {
      v.verdict = "accepted";
      if (c.edge_match != c.match)
        v.reason += (v.reason.empty() ? "" : " ") + ("edge to keyframe " + std::to_string(c.edge_match)) +
                    ", which saw the most PnP inliers";
    } else if (v.verdict.empty()) {
      v.verdict = "pose_graph";
      v.reason = "verified, but not admitted by the pose graph's consistency test";
    }
    verdicts.push_back(std::move(v));
  }
  return verdicts;
}

LoopDetector asLoopDetector(const BowLoopDetector::Ptr& detector) {
  if (!detector) throw std::invalid_argument("asLoopDetector: no detector");
  return [detector](const frontend::Map& map, frontend::KeyframeId query) { return detector->detect(map, query); };
}

}  // namespace weighted_icp::mapping
