#pragma once
// Pose-graph optimisation of keyframe poses (SE(3) as position + unit quaternion
// on Ceres' EigenQuaternionManifold, Levenberg-Marquardt): odometry edges from
// tracking, loop edges from place recognition, each loop admitted only if the
// graph can take it (an incremental chi-square test), so one wrong loop cannot
// wreck the map.

#include <cstddef>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "weighted_icp/frontend/slam/map_point.h"
#include "weighted_icp/mapping/loop_constraint.h"

namespace weighted_icp::mapping {

/// @brief 6x6 information of a relative pose, ordered (translation x y z, rotation x y z).
using Information6d = Eigen::Matrix<double, 6, 6>;

/// @brief What an edge says.
enum class PoseGraphEdgeKind {
  Odometry,  ///< consecutive keyframes, from tracking and bundle adjustment
  Loop       ///< a recognised revisit (or a merge between sessions)
};

/// @brief A relative-pose measurement between two nodes: x_from = to_in_from * x_to.
struct PoseGraphEdge {
  /// @brief The older node (the loop's match).
  frontend::KeyframeId from = 0;
  /// @brief The newer node (the loop's query).
  frontend::KeyframeId to = 0;
  /// @brief Pose of `to` in the frame of `from`.
  Eigen::Isometry3d to_in_from = Eigen::Isometry3d::Identity();
  /// @brief Inverse covariance of to_in_from; the error is (translation in `from`'s frame, rotation vector of
  /// measured^-1 * estimated), as LoopConstraint documents.
  Information6d information = Information6d::Identity();
  /// @brief Odometry edges are always kept; loop edges go through the consistency test and a Huber loss.
  PoseGraphEdgeKind kind = PoseGraphEdgeKind::Odometry;
  /// @brief A loop edge an earlier optimisation admitted (a loop closer's accepted loops): such loops are tested
  /// together first, in one solve, and one by one only if together they fail (PoseGraph::optimize).
  bool admitted_before = false;
};

/// @brief The loop edge LoopConstraint describes (from = match, to = query).
/// @param loop A verified loop.
PoseGraphEdge loopEdge(const LoopConstraint& loop);

/// @brief How much a consecutive-keyframe edge is trusted: the documented odometry noise model.
///
/// Standard deviations grow with the motion of the edge, as visual odometry drift does:
/// sigma_t = translation_sigma_m + translation_sigma_per_m * |t| (metres, each axis) and
/// sigma_r = rotation_sigma_rad + rotation_sigma_per_rad * angle (radians, each axis). The defaults are
/// deliberately wider than the front end's drift on the TUM heads (about 1-2 % of the path): an odometry
/// that is too confident would make the consistency test refuse correct loops after a long excursion.
struct OdometryNoiseModel {
  /// @brief Translation standard deviation at no motion, metres.
  double translation_sigma_m = 0.01;
  /// @brief Added translation standard deviation per metre travelled.
  double translation_sigma_per_m = 0.05;
  /// @brief Rotation standard deviation at no motion, radians (0.3 deg).
  double rotation_sigma_rad = 0.3 * 3.14159265358979323846 / 180.0;
  /// @brief Added rotation standard deviation per radian turned.
  double rotation_sigma_per_rad = 0.05;
  /// @brief Information is divided by this across a tracking loss (a new segment starts at the last known pose,
  /// which is a guess, not a measurement).
  double segment_break_factor = 1e4;
};

/// @brief The information of one odometry edge under `model`.
/// @param relative The measured relative pose (to_in_from).
/// @param model The noise model.
/// @param across_segments True when the edge spans a tracking loss.
Information6d odometryInformation(const Eigen::Isometry3d& relative, const OdometryNoiseModel& model,
                                  bool across_segments = false);

/// @brief Options of PoseGraph::optimize.
struct PoseGraphOptions {
  /// @brief Levenberg-Marquardt iterations per solve.
  int max_iterations = 50;
  /// @brief A loop is admitted when adding it raises the optimised cost (sum of squared whitened residuals) by
  /// at most this: chi-square with 6 degrees of freedom at 99.9 %. It compares the loop with everything already
  /// in the graph, through the joint covariance of the chain between its ends, which a per-edge residual cannot.
  double loop_chi2_gate = 22.458;
  /// @brief Huber threshold on the whitened loop residual (sigmas). Convex, so unlike a redescending loss it
  /// cannot trap the solver in the un-closed state after a long drift; it bounds what an admitted loop pulls.
  double loop_huber = 4.739;  // sqrt(loop_chi2_gate)
  /// @brief Ceres threads; the result does not depend on them beyond the last bits.
  int threads = 1;
};

/// @brief What one optimisation did.
struct PoseGraphSummary {
  /// @brief False when the solver failed; the poses are then left as they were.
  bool ok = false;
  /// @brief Why, when not ok.
  std::string message;
  /// @brief Per edge (in addEdge order): false for a loop edge the consistency test refused.
  std::vector<bool> edge_used;
  /// @brief Loop edges admitted / refused.
  std::size_t loops_used = 0;
  std::size_t loops_rejected = 0;
  /// @brief Final cost: half the sum of squared (robustified) whitened residuals of the used edges.
  double final_cost = 0.0;
  /// @brief Ceres solves run (one for the odometry, one for the loops admitted before if any, one per loop edge
  /// tested alone).
  std::size_t solves = 0;
};

/// @brief A pose graph of keyframes (nodes keyed by id, camera-to-world poses) and relative-pose edges.
class PoseGraph {
 public:
  using Ptr = std::shared_ptr<PoseGraph>;
  using ConstPtr = std::shared_ptr<const PoseGraph>;

  /// @brief Adds (or replaces) a node.
  /// @param id Node id (a keyframe id).
  /// @param pose_wc Initial camera-to-world pose; throws std::invalid_argument if not finite.
  /// @param fixed A fixed node fixes the gauge; if none is fixed, the smallest id is.
  void addNode(frontend::KeyframeId id, const Eigen::Isometry3d& pose_wc, bool fixed = false);
  /// @brief Adds an edge; throws std::invalid_argument for an unknown node, equal ends, a non-finite pose or an
  /// information matrix that is not symmetric positive definite.
  /// @param edge The measurement.
  void addEdge(const PoseGraphEdge& edge);

  /// @brief Optimises: odometry first, then the loop edges in addEdge order, each admitted only if it passes the
  /// chi-square gate against the graph so far; the poses end at the optimum with the admitted loops.
  /// Loop edges marked admitted_before (two or more) are first tested together, against the chi-square gate of their
  /// joint degrees of freedom at the same probability as loop_chi2_gate's: one solve where a loop closer that
  /// re-tested every earlier loop at each closure ran one per loop. If together they fail, each is tested alone.
  /// @param options Solver and gate settings.
  PoseGraphSummary optimize(const PoseGraphOptions& options = {});

  /// @brief Current node poses (camera-to-world), by id.
  const std::map<frontend::KeyframeId, Eigen::Isometry3d>& poses() const { return poses_; }
  /// @brief The edges, in addEdge order.
  const std::vector<PoseGraphEdge>& edges() const { return edges_; }
  /// @brief "PoseGraph".
  static std::string getClassName() { return "PoseGraph"; }

 private:
  struct Solve {
    bool ok = false;
    std::string message;
    double cost = 0.0;
  };
  /// One Levenberg-Marquardt solve over the given edges, starting from and writing into `poses`.
  Solve solve(const std::vector<bool>& use, std::map<frontend::KeyframeId, Eigen::Isometry3d>& poses,
              const PoseGraphOptions& options) const;
  /// optimize's first step after the odometry: the loops admitted before, two or more, tested together; if they pass,
  /// they are marked used in `summary`, and `poses` and `current` become that solve's.
  void admitEarlierLoopsTogether(const PoseGraphOptions& options, PoseGraphSummary& summary,
                                 std::map<frontend::KeyframeId, Eigen::Isometry3d>& poses, Solve& current) const;

  std::map<frontend::KeyframeId, Eigen::Isometry3d> poses_;
  std::map<frontend::KeyframeId, bool> fixed_;
  std::vector<PoseGraphEdge> edges_;
};

}  // namespace weighted_icp::mapping
