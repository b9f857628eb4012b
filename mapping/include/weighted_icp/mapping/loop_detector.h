#pragma once
// The loop detector the loop closer calls: place recognition proposes older
// keyframes that look like the new one, geometric verification (bounded by the
// odometry's drift) accepts the first whose geometry agrees. The piece that
// turns PlaceRecognizer and LoopVerifier into a LoopDetector.
#include <cstddef>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "weighted_icp/core/camera.h"
#include "weighted_icp/mapping/binary_vocabulary.h"
#include "weighted_icp/mapping/loop_closer.h"
#include "weighted_icp/mapping/loop_verifier.h"
#include "weighted_icp/mapping/place_recognizer.h"

namespace weighted_icp::mapping {

/// @brief Options of BowLoopDetector.
struct LoopDetectorOptions {
  /// @brief Candidate search (exclusions, score thresholds, temporal consistency).
  PlaceRecognitionOptions recognition;
  /// @brief Geometric verification (PnP, weighted ICP check).
  LoopVerificationOptions verification;
  /// @brief How far from the odometry's estimate a verified pose may be (the drift the run can have).
  DriftBounds drift;
  /// @brief false: verification without the odometry prior (any pose the geometry supports).
  bool use_odometry_prior = true;
  /// @brief Segment bridges: each of the first this many keyframes of a segment (a new one starts after tracking
  /// was lost, at a guess), as it arrives and until one passes, is verified against the previous segment's last
  /// keyframe from any pose, before place recognition: the likeliest view of the same place, which place
  /// recognition's temporal consistency proposes late if at all, once the camera has moved on. 0: off.
  std::size_t bridge_keyframes = 3;
};

/// @brief One candidate place recognition proposed, and what geometric verification made of it.
struct LoopCandidateRecord {
  /// @brief The query keyframe and the proposed older keyframe.
  frontend::KeyframeId query = 0, match = 0;
  /// @brief Place recognition's normalised score.
  double score = 0.0;
  /// @brief The check that refused it (LoopVerification::refused_by, or "culled" for a keyframe bundle adjustment
  /// removed since); empty when verified.
  std::string refused_by;
  /// @brief Why, with the measured values; empty when verified.
  std::string reason;
  /// @brief The keyframe the verified loop's edge joins (LoopConstraint::match: with the PnP edge, the candidate's
  /// neighbour that saw the most of PnP's inliers, often the candidate itself); the candidate when refused.
  frontend::KeyframeId edge_match = 0;
};

/// @brief What the detector did so far (for reports and tests); the candidate counts are those of candidates().
struct LoopDetectorStats {
  /// @brief Keyframes queried.
  std::size_t queries = 0;
  /// @brief Candidates place recognition proposed (after temporal consistency).
  std::size_t candidates = 0;
  /// @brief Candidates geometric verification accepted (one per query at most is returned).
  std::size_t verified = 0;
};

/// @brief Place recognition + geometric verification over one front-end map. Not thread-safe: the loop closer
/// calls it from one thread, one keyframe at a time, in insertion order.
class BowLoopDetector {
 public:
  using Ptr = std::shared_ptr<BowLoopDetector>;

  /// @brief Throws std::invalid_argument without a vocabulary.
  /// @param vocabulary The trained vocabulary (shared, read only).
  /// @param camera The camera of the sequence (verification's PnP).
  /// @param options See LoopDetectorOptions.
  BowLoopDetector(BinaryVocabulary::ConstPtr vocabulary, const PinholeCamera& camera, LoopDetectorOptions options = {});

  /// @brief Queries the map's keyframe `query` against the keyframes seen before, then adds it to the database.
  /// @param map The SLAM map (read through one snapshot under its lock).
  /// @param query The keyframe just inserted.
  /// @return The best-scoring verified loop (score = place recognition's normalised score), or nothing.
  std::optional<LoopConstraint> detect(const frontend::Map& map, frontend::KeyframeId query);

  /// @brief Counters so far (read it when detect() is not running, as candidates()).
  LoopDetectorStats stats() const;
  /// @brief Every candidate so far, in the order verified (a query's candidates best first), with its verdict:
  /// why a run closed no loop. Read it when detect() is not running (after the loop closer has finished). It grows
  /// by at most PlaceRecognitionOptions::max_places records a keyframe and is kept whole for the run's
  /// loop_candidates.txt.
  const std::vector<LoopCandidateRecord>& candidates() const { return candidates_; }

  /// @brief "BowLoopDetector".
  static std::string getClassName() { return "BowLoopDetector"; }

 private:
  BinaryVocabulary::ConstPtr vocabulary_;
  PlaceRecognizer recognizer_;
  LoopVerifier verifier_;
  LoopVerifier bridge_verifier_;  // verifier_'s options without the ICP (LoopVerificationOptions::icp_check)
  /// The previous segment's last keyframe when `query` is among the first bridge_keyframes of a segment not yet
  /// bridged; nothing otherwise.
  std::optional<frontend::KeyframeId> bridgeCandidate(const KeyframeSnapshot& snapshot,
                                                      frontend::KeyframeId query) const;

  LoopDetectorOptions options_;
  std::set<std::size_t> bridged_segments_;
  std::size_t queries_ = 0;
  std::vector<LoopCandidateRecord> candidates_;
};

/// @brief A candidate's verdict once the run is over (loop_candidates.txt; where to look when a run closes no loop).
struct LoopCandidateVerdict {
  /// @brief What the detector recorded.
  LoopCandidateRecord candidate;
  /// @brief "accepted" (its loop was admitted), "pose_graph" (verified, but not admitted by the pose graph's
  /// consistency test) or the verification check that refused it (LoopCandidateRecord::refused_by).
  std::string verdict;
  /// @brief Why, with the measured values; for an accepted loop whose edge joins another keyframe than the
  /// candidate, which one.
  std::string reason;
};

/// @brief The verdict of every candidate, in the detector's order.
/// @param candidates What BowLoopDetector::candidates() recorded.
/// @param accepted The loops admitted (LoopCloser::acceptedLoops(), LoopClosingSlam::acceptedLoops()).
std::vector<LoopCandidateVerdict> candidateVerdicts(const std::vector<LoopCandidateRecord>& candidates,
                                                    const std::vector<LoopConstraint>& accepted);

/// @brief The detector in the form LoopCloser and LoopClosingSlam take; the returned function shares `detector`.
/// @param detector The detector (not null: std::invalid_argument).
LoopDetector asLoopDetector(const BowLoopDetector::Ptr& detector);

}  // namespace weighted_icp::mapping
