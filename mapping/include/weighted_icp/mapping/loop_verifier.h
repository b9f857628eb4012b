#pragma once
// Geometric verification of a place-recognition candidate: descriptor
// matches from the query keyframe to the candidate's landmarks, RANSAC PnP for
// the relative pose from any starting rotation, then the paper's weighted ICP
// between the two local landmark clouds to check and refine it.

#include <cstddef>
#include <optional>
#include <string>

#include "weighted_icp/core/camera.h"
#include "weighted_icp/frontend/geometry/pose_estimation.h"
#include "weighted_icp/mapping/keyframe_snapshot.h"
#include "weighted_icp/mapping/loop_constraint.h"
#include "weighted_icp/registration/weight_strategies.h"

namespace weighted_icp::mapping {

/// @brief Which of the two measurements of a verified loop becomes its edge.
enum class LoopEdgeSource {
  /// PnP's pose from the descriptor matches (true correspondences, pixel-accurate), with the Gauss-Newton
  /// information of its reprojection residuals; the weighted ICP only checks it. On synthetic loops PnP alone was
  /// mostly within 0.05-0.3 cm of the truth, the ICP-refined pose 0.1-1.6 cm (its nearest neighbours are not true
  /// correspondences), so the default.
  Pnp,
  /// The weighted ICP's refinement of the PnP pose, with the Hessian of its point-to-point residuals (before
  /// issue #6's drift work; kept for comparison).
  Icp
};

/// @brief "pnp" or "icp", the name parseLoopEdgeSource reads. @param source the edge's source
std::string toString(LoopEdgeSource source);
/// @brief The source named "pnp" or "icp". @param name the name
/// @throws std::invalid_argument "unknown loop edge source '<name>' (expected pnp or icp)"
LoopEdgeSource parseLoopEdgeSource(const std::string& name);

/// @brief What a loop must show to be accepted.
struct LoopVerificationOptions {
  /// Keyframes either side of the candidate (same segment) whose landmarks form its local map: what the
  /// query's features are matched to and the ICP target.
  std::size_t neighbour_keyframes = 5;
  /// Keyframes either side of the query whose landmarks form the ICP source (its mini-map). With 0 (the
  /// query's own landmarks only) the weighted stage's pull towards heavy points, unbalanced by the rest of the
  /// mini-map, moved PnP poses right to 1 cm by 0.2-0.8 m on synthetic loops, and 6 of 9 true loops were refused.
  std::size_t query_neighbour_keyframes = 5;
  /// A descriptor match needs a Hamming distance of at most this (of 256 bits) ...
  int max_hamming_distance = 64;
  /// ... and below this fraction of the second-best distance (Lowe's ratio test).
  double ratio = 0.8;
  /// RANSAC PnP (the front end's: AP3P + EPnP, then Huber refinement).
  frontend::PnpOptions pnp{200, 3.0, 0.999, 12, 2.0, 20};
  /// PnP inliers needed, and, with LoopEdgeSource::Icp, PnP inliers the ICP's camera pose must still explain
  /// (project within the PnP reprojection threshold).
  std::size_t min_inliers = 30;
  /// Weighted ICP between the local landmark clouds, started from the PnP pose: the weight strategy, the
  /// neighbours it chooses among, and the correspondence limit (metres) that keeps the parts without a
  /// counterpart out.
  WeightStrategy weight = WeightStrategy::Covariance;
  unsigned int k = 5;
  double icp_max_correspondence_m = 0.10;
  /// Points of the query's cloud closer than this (metres) to the candidate's after ICP are overlap inliers.
  double inlier_distance_m = 0.05;
  /// At least this fraction of the query cloud's points must be overlap inliers ...
  double min_overlap = 0.25;
  /// ... and PCL's fitness over them (mean squared distance, m^2) at most this.
  double max_fitness = 0.03 * 0.03;
  /// ICP may move the PnP pose by at most this much (metres, degrees): more means PnP and the landmark
  /// geometry disagree, and two measurements of one loop farther apart than what counts as a wrong loop (5 cm or
  /// 2 degrees) cannot both be right. Until 2026-11-26 10 cm / 5 degrees: PnP poses 7-10 cm and 1-1.4 degrees off
  /// (landmarks on one far wall, where a rotation and a translation look alike) passed with ICP 7-10 cm away,
  /// near the truth (docs/mapping.md).
  double max_icp_correction_m = 0.05;
  double max_icp_correction_deg = 2.0;
  /// Which pose (and information) the accepted loop carries.
  LoopEdgeSource edge = LoopEdgeSource::Pnp;
  /// PnP edge: the pixel noise is taken as the inliers' reprojection RMS, but never below this (pixels per
  /// coordinate), so a lucky fit does not claim sub-pixel features.
  double min_pixel_sigma_px = 0.5;
  /// Variance factor on the accepted loop's covariance (its information is divided by it), for what the PnP or
  /// ICP Hessian cannot see on a real sensor; 10, as TrackingInformationOptions::covariance_inflation and for the
  /// same measurement (docs/mapping.md, "Real revisits"). Both alike keep the pose graph's optimum (but for the
  /// floors and the Huber loss) and widen its consistency test.
  double covariance_inflation = 10.0;
  /// false: no ICP; the clouds' overlap and fitness are measured at PnP's pose. For a segment bridge
  /// (LoopDetectorOptions::bridge_keyframes): the new segment's first keyframe has single-view landmarks, on which
  /// ICP slid 1.3-4.4 cm from PnP poses 0.2-1.6 cm from the truth while the overlap rose by under 0.01
  /// (docs/mapping.md, "Bridging a tracking loss").
  bool icp_check = true;
};

/// @brief What the odometry says of a loop in one session: the relative pose its (drifting) keyframe poses
/// imply, and how far a true loop may differ from it. Repeated texture can fool both appearance and the local
/// geometry (a room corner looks like every other corner), but it cannot make a loop that would need the
/// odometry to have drifted by 90 degrees over a few metres.
struct LoopPrior {
  /// @brief match_wc^-1 * query_wc from the odometry.
  Eigen::Isometry3d expected_query_in_match = Eigen::Isometry3d::Identity();
  /// @brief Largest translation (metres) and rotation (degrees) between the verified and the expected pose.
  double max_translation_m = 0.0, max_rotation_deg = 0.0;
};

/// @brief How much drift a loop may correct in one session: a floor plus a share of the path travelled
/// between the two keyframes.
struct DriftBounds {
  /// Metres allowed whatever the path, and per metre of path.
  double translation_floor_m = 0.3, translation_per_metre = 0.1;
  /// Degrees allowed whatever the path, and per metre of path.
  double rotation_floor_deg = 10.0, rotation_per_metre_deg = 1.0;
};

/// @brief The odometry prior of a loop between two keyframes of one snapshot: their relative pose, and bounds
/// that grow with the path length (the sum of the translations between consecutive keyframes from `match` to
/// `query`).
/// @param map the session's keyframes
/// @param query the newer keyframe; unknown throws std::invalid_argument
/// @param match the older keyframe; unknown throws std::invalid_argument
/// @param bounds the allowed drift
LoopPrior odometryPrior(const KeyframeSnapshot& map, frontend::KeyframeId query, frontend::KeyframeId match,
                        const DriftBounds& bounds = {});

/// @brief The outcome of one verification, accepted or not, with what it measured.
struct LoopVerification {
  /// @brief True when every test passed; `constraint` is then the loop.
  bool accepted = false;
  /// @brief The check that refused it, a stable short name (empty when accepted): descriptor_matches, pnp,
  /// pnp_inliers, icp_landmarks, icp_degenerate, icp_correction, icp_inliers, overlap, fitness or drift.
  std::string refused_by;
  /// @brief Why it was refused, with the measured values (empty when accepted).
  std::string reason;
  /// @brief The loop (query, match, relative pose, information, inliers, fitness); score left to the caller.
  LoopConstraint constraint;
  /// @brief Descriptor matches that passed the distance and ratio tests.
  std::size_t matches = 0;
  /// @brief Fraction of the query cloud's points within inlier_distance_m after ICP.
  double overlap = 0.0;
  /// @brief The relative pose PnP alone gave (before the ICP), the query camera in the candidate's (`match` of
  /// verify()) camera frame.
  Eigen::Isometry3d pnp_query_in_match = Eigen::Isometry3d::Identity();
  /// @brief False when, verified with an odometry prior, the weighted ICP's result overlapped the candidate's cloud
  /// less than PnP's pose did (it left the pose instead of refining it): the checks, and with LoopEdgeSource::Icp
  /// the edge, are then plain ICP's (k = 1). Without a prior the weighted ICP's result is always the one checked.
  /// False too with LoopVerificationOptions::icp_check off (no ICP ran).
  bool icp_weighted = true;
  /// @brief How far ICP moved the PnP pose (metres, degrees).
  double icp_correction_m = 0.0, icp_correction_deg = 0.0;
  /// @brief How many PnP inliers the ICP's camera pose still projects within the PnP reprojection threshold. With
  /// LoopEdgeSource::Icp the loop is refused below min_inliers (the ICP's pose, which would be the loop, left the
  /// solution the descriptor matches support); with the PnP edge the correction bound alone judges the agreement.
  std::size_t icp_explained_inliers = 0;
};

/// @brief Verifies loop candidates. Stateless apart from its settings: one instance may serve several threads.
class LoopVerifier {
 public:
  /// @brief A verifier for keyframes taken with one camera.
  /// @param camera undistorted pinhole model of the keyframes' pixels
  /// @param options thresholds; non-positive distances or fractions out of [0, 1] throw std::invalid_argument
  explicit LoopVerifier(const PinholeCamera& camera, LoopVerificationOptions options = {});

  /// @brief The class name, as PCL classes report it.
  static std::string getClassName() { return "LoopVerifier"; }
  /// @brief The options in use.
  const LoopVerificationOptions& options() const { return options_; }

  /// @brief Verifies that keyframe `query` of `query_map` sees the place of keyframe `match` of `match_map`
  /// (the same map for a loop, two sessions for a merge).
  ///
  /// The query's features are matched to the landmarks of the match's neighbourhood; RANSAC PnP gives the
  /// query camera's pose in the match map's frame; the query's local landmark cloud, moved by it, is aligned
  /// to the match's by the weighted ICP with refinement, which must agree with PnP. With LoopEdgeSource::Pnp (the
  /// default) the loop joins the keyframe of the candidate's neighbourhood that observed the most of PnP's inlier
  /// landmarks (the candidate on a tie): PnP placed the camera among those landmarks, which sit where that keyframe's
  /// pose put them, while the candidate's pose may differ from its neighbours' by their drift (constraint.match);
  /// query_in_match is PnP's pose relative to it and the information the Gauss-Newton
  /// Hessian of the inliers' reprojection residuals, each whitened by the pixel noise plus its landmark's projected
  /// covariance. With LoopEdgeSource::Icp it is match_wc^-1 * correction * query_wc and the Hessian of the ICP's
  /// point-to-point residuals, whitened by both landmarks' covariances (docs/place_recognition.md).
  /// @param query_map the map holding the query keyframe
  /// @param query its id; unknown throws std::invalid_argument
  /// @param match_map the map holding the candidate
  /// @param match the candidate's id; unknown throws std::invalid_argument
  /// @param prior for a loop within one session, odometryPrior(): a result farther from it is refused. None for
  /// two sessions (their frames are unrelated), where geometry alone decides.
  LoopVerification verify(const KeyframeSnapshot& query_map, frontend::KeyframeId query,
                          const KeyframeSnapshot& match_map, frontend::KeyframeId match,
                          const std::optional<LoopPrior>& prior = std::nullopt) const;

 private:
  PinholeCamera camera_;
  LoopVerificationOptions options_;
};

}  // namespace weighted_icp::mapping
