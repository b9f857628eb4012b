#pragma once
// The up direction of a map, from its cameras: a camera held upright (a robot's,
// a hand-held one) keeps its image rows level whatever its heading and pitch, so
// the up axis is the direction most nearly perpendicular to every camera's x
// axis. The global search rotates about the up axis the two maps share; a SLAM
// that writes its map in the first camera's frame (ORB-SLAM's, our front end's)
// has its up axis near -y there, not z, and two such maps share none until each
// is levelled by its own.

#include <cstddef>
#include <map>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "weighted_icp/registration/landmark_map.h"

namespace weighted_icp {

/// @brief The up direction a map's camera poses suggest.
struct UpAxisEstimate {
  /// Unit vector in the map's frame; +z when there is no camera.
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  /// Root-mean-square angle between the cameras' image rows and the plane perpendicular to `axis` (degrees):
  /// how level the rows are about it (the paper's real map: 6.9°, a hand-held TUM camera's roll).
  double row_tilt_deg = 0.0;
  /// Camera poses the estimate came from.
  std::size_t cameras = 0;
  /// True when the rows' headings varied enough to fix the axis by themselves; false when it is the cameras'
  /// mean down direction (-y) made perpendicular to their common rows (one heading, or a single camera).
  bool from_rows = false;
  /// The cameras' main row direction (unit; the outer products' largest eigenvector, signed along the cameras' mean
  /// x axis): the axis about which the estimate is least sure when the headings vary little (a camera's pitch, or its
  /// roll over few headings).
  Eigen::Vector3d rows = Eigen::Vector3d::UnitX();
  /// How much the headings vary: the outer products' second eigenvalue (0 for one heading; sin^2 of half the angle
  /// between two headings; 0.5 for headings all round).
  double heading_spread = 0.0;
};

/// @brief Estimates the up axis from camera-to-world poses: the eigenvector of the smallest eigenvalue of the
/// sum of the cameras' x axes' outer products, signed so that the cameras' mean y axis points down along it.
/// @param camera_poses  camera-to-world poses (x right along the image rows, y down the image, z forward)
/// @param min_heading_spread  smallest second eigenvalue (of the outer products' mean, whose eigenvalues sum
///        to 1) for the rows alone to fix the axis: 0.03 is two headings 20° apart; below it the rows fix
///        only a plane and the mean down direction chooses within it
UpAxisEstimate estimateUpAxis(const std::map<FrameId, Eigen::Isometry3d>& camera_poses,
                              double min_heading_spread = 0.03);

/// @brief The axes the global search levels a source and a target map by.
struct SharedUpAxes {
  Eigen::Vector3d source = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d target = Eigen::Vector3d::UnitZ();
  /// How far the two axes may disagree, for GlobalAlignmentSettings::tilt_range_deg: 0 for axes known to be
  /// shared, 8° for axes estimated from each map's cameras (a hand-held camera's roll drifts: mini-maps of the
  /// paper's real map, a third to two thirds of its frames, estimate their up axis 0.4-7.2° off the truth), and
  /// for maps that count as z-up twice chooseUpAxes's z tolerance (at most kMaxTiltRangeDeg): either may be
  /// that far off gravity, and a turn about gravity doubles a common tilt (since 2026-11-28; a map 6° off gravity:
  /// 70 -> 84 of 100 pairs found, every z-up sweep unchanged case for case, about 1.5 times the time).
  double tilt_range_deg = 0.0;
  /// Search about the maps' z axis as well, and keep whichever search's source points have the closer counterparts
  /// (the higher GlobalAlignmentResult::inlier_score): the estimates are a guess, and two maps of one frame displaced
  /// about its z axis (as a test of a map written in a camera's frame would) share z exactly.
  bool also_try_z = false;
  /// Further levellings, each as (source axis, target axis) with tilt_range_deg, the one whose search has the highest
  /// inlier score kept (ties to the earlier, the estimates' own first): a map whose cameras face about one way fixes
  /// its up axis only to within a turn about their rows (chooseUpAxes). Of more than kAlternativesSearchedFully,
  /// GlobalLandmarkAligner::align(source, axes) searches fully only those a cheap first look scores highest.
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> alternatives;
  /// True when both are +z and nothing else is tried.
  bool zUpOnly() const {
    return !also_try_z && alternatives.empty() && source == Eigen::Vector3d::UnitZ() &&
           target == Eigen::Vector3d::UnitZ();
  }
};

/// @brief The turns about a map's rows direction (degrees) at which chooseUpAxes also levels a map whose cameras face
/// about one way: 15° apart, so that with the search's tilts of 8° each way they cover 53° each way of the estimate
/// (a camera looking down at a desk: fr1 xyz's 42°; fr3 teddy's mini-maps 22-24°, the real map's 12-37° off).
inline const std::vector<double> kPitchedLevellingsDeg = {-15.0, 15.0, -30.0, 30.0, -45.0, 45.0};

/// @brief Up axes a map's estimate may be turned to when its cameras face about one way: the estimate turned about
/// its rows direction (UpAxisEstimate::rows) by each of `pitches_deg`, when its heading spread is below `max_spread`;
/// none otherwise.
/// @param estimate  estimateUpAxis() of the map
/// @param max_spread  heading spread below which the estimate is searched pitched
/// @param pitches_deg  turns about the rows direction, in degrees
std::vector<Eigen::Vector3d> pitchedUpAxes(const UpAxisEstimate& estimate, double max_spread,
                                           const std::vector<double>& pitches_deg);

/// @brief Chooses the up axes for aligning `source` onto `target`: +z for both when both maps' estimated up
/// axes are within `z_tolerance_deg` of ±z (maps written gravity-aligned, as the paper's and TUM's: levelling
/// such maps by their estimates would only add the estimates' own errors), searched with tilts of up to twice
/// the tolerance; +z without tilts when either map has no camera; otherwise each map's own estimate with tilts,
/// and z tried as well, and for a map whose cameras face about one way its estimate turned about their rows.
/// @param source_estimate  estimateUpAxis() of the source map
/// @param target_estimate  estimateUpAxis() of the target map
/// @param z_tolerance_deg  largest angle to ±z for a map to count as z-up: 8° by default, just above the
///        estimates' own error on a z-up map (the paper's real map: 3.4° whole, 0.4-7.2° for its mini-maps), so
///        that a map written 10-15° off gravity is levelled rather than searched about a wrong axis (15° until
///        2026-11-27: 53-58 of 100 such pairs found, 90 since; docs/global_alignment.md)
/// @param pitch_search_spread  for maps levelled by their own estimates: a map whose heading spread
///        (UpAxisEstimate::heading_spread) is below this is also searched levelled by its estimate turned about its
///        rows by each of kPitchedLevellingsDeg (SharedUpAxes::alternatives: the other map by its own estimate, or,
///        when its spread is below this too, turned by the same angle about its own rows, as one camera's pitch
///        would put both off). 0.2 is two headings 53° apart (a mini-map of the real map with a spread of 0.17
///        estimates 12° off); 0 for none (docs/global_alignment.md, "Cameras that face one way")
SharedUpAxes chooseUpAxes(const UpAxisEstimate& source_estimate, const UpAxisEstimate& target_estimate,
                          double z_tolerance_deg = 8.0, double pitch_search_spread = 0.2);

}  // namespace weighted_icp
