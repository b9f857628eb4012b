#pragma once
// One loop as Python reads it (weighted_icp.Loop): a run's loop closure or a merge's loop between sessions, its
// keyframes named by session, id and timestamp.

#include <cstddef>
#include <cstdint>

#include <Eigen/Core>

#include "weighted_icp/mapping/loop_constraint.h"

namespace weighted_icp::python {

/// @brief A loop: the query keyframe's camera in the match keyframe's, and how it was verified.
struct LoopRecord {
  /// @brief Sessions of the two keyframes (0 within one run; the merge's input order otherwise).
  std::size_t query_session = 0, match_session = 0;
  /// @brief Keyframe ids within their sessions.
  std::uint64_t query = 0, match = 0;
  /// @brief Their timestamps (seconds, as in the input sequence).
  double query_timestamp = 0.0, match_timestamp = 0.0;
  /// @brief Camera-to-camera pose: x_match = query_in_match * x_query.
  Eigen::Matrix4d query_in_match = Eigen::Matrix4d::Identity();
  /// @brief PnP inliers, the weighted ICP check's fitness (m^2), place recognition's score.
  std::size_t inliers = 0;
  double fitness = 0.0, score = 0.0;
  /// @brief Whether the pose graph's consistency test admitted it (a run's loops always were).
  bool used = true;
};

/// @brief The record of `loop`, whose keyframe ids are session * stride + id (stride 0: one session).
/// @param loop             the loop
/// @param stride           the id stride of the sessions (MiniMapGraph::kSessionIdStride), or 0
/// @param query_timestamp  the query keyframe's timestamp
/// @param match_timestamp  the match keyframe's timestamp
/// @param used             whether the pose graph admitted it
inline LoopRecord toLoopRecord(const mapping::LoopConstraint& loop, std::uint64_t stride, double query_timestamp,
                               double match_timestamp, bool used) {
  LoopRecord record;
  record.query_session = stride == 0 ? 0 : static_cast<std::size_t>(loop.query / stride);
  record.match_session = stride == 0 ? 0 : static_cast<std::size_t>(loop.match / stride);
  record.query = stride == 0 ? loop.query : loop.query % stride;
  record.match = stride == 0 ? loop.match : loop.match % stride;
  record.query_timestamp = query_timestamp;
  record.match_timestamp = match_timestamp;
  record.query_in_match = loop.query_in_match.matrix();
  record.inliers = loop.inliers;
  record.fitness = loop.fitness;
  record.score = loop.score;
  record.used = used;
  return record;
}

}  // namespace weighted_icp::python
