#pragma once
// Alignment from any start, from geometry alone: a search over rotations about
// the up axis with a translation vote per rotation, each promising hypothesis
// refined by a trimmed ICP whose distance limit shrinks with the residual, the
// best kept by how many source points find a target point close by.
//
// The algorithm works on plain xyz clouds; global_landmark_alignment.h is the
// landmark adapter that finishes with the paper's weighted ICP.

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <Eigen/Core>

namespace weighted_icp {

/// @brief The widest tilt range (degrees) GlobalAlignment searches: its settings' and align()'s tilt_range_deg are
/// refused beyond it, and chooseUpAxes() never asks for more.
inline constexpr double kMaxTiltRangeDeg = 30.0;

class WorkerPool;

/// @brief Parameters of the global search. Lengths in metres; those left at 0
/// are derived from the target's point spacing (the median distance from a
/// target point to its nearest other target point), so one set of defaults
/// serves sparse and dense maps alike.
struct GlobalAlignmentSettings {
  /// Rotations tried about `up_axis`, evenly spaced over 360°: 72 is a 5° step, so the best one is at most 2.5°
  /// off. 36 until 2026-11-29: pieces of the real map sharing 6 of 240 frames were then found in 22 of 35 cases
  /// (72: 35), the map in its first camera's frame in 95 of 100 (72: 100), for about a quarter more CPU; 72 needs
  /// tilted_hypotheses 6 (docs/global_alignment.md).
  unsigned int yaw_hypotheses = 72;
  /// The target's up axis, and the source's unless align() is given its own
  /// (gravity for maps built upright, as the paper's and TUM's; up_axis.h
  /// estimates it from a map's cameras); the search does not try tilts about
  /// other axes.
  Eigen::Vector3d up_axis = Eigen::Vector3d::UnitZ();
  /// Translation vote cell. 0: 15 cm; large enough to gather the votes of a
  /// rotation up to 5° off at a metre from the centre.
  double vote_cell = 0.15;
  /// Voxel size for the sample the vote and the hypothesis ICP use; 0: vote_cell / 3.
  double sample_cell = 0.0;
  /// Caps on the sample sizes (the vote costs their product per rotation).
  std::size_t max_source_samples = 400;
  std::size_t max_target_samples = 1500;
  /// Vote peaks kept per rotation, and hypotheses (best voted overall) refined.
  unsigned int peaks_per_rotation = 3;
  unsigned int refined_hypotheses = 12;
  /// Fine search around each refined hypothesis: rotations within
  /// ±fine_yaw_range_deg in fine_yaw_step_deg steps, translations within
  /// ±fine_window of the hypothesis voted in fine_cell cells with every target
  /// point (not a sample), so the pose where many points have a close
  /// counterpart stands out even where the maps share only part of the scene.
  /// Two levels: first ±fine_yaw_range_deg in medium_yaw_step_deg steps with
  /// medium_cell cells within ±fine_window, then ±medium_yaw_step_deg in
  /// fine_yaw_step_deg steps with fine_cell cells within ±2 medium cells.
  double fine_yaw_range_deg = 6.0;
  double medium_yaw_step_deg = 1.5;
  double fine_yaw_step_deg = 0.5;
  double fine_window = 0.3;
  double medium_cell = 0.05;
  double fine_cell = 0.02;
  /// The `climbed_hypotheses` best refined hypotheses are searched again (medium and fine vote, trimmed ICP) from
  /// where their trimmed ICP ended, at most `climb_rounds` times while their inlier score grows: a vote reaches only
  /// fine_yaw_range_deg and fine_window from its start, and a coarse hypothesis next to the truth's can end a
  /// little beyond that, short of it. The one with the highest inlier score wins over the results as refined; the tilts
  /// below start from those results, not the climbed ones. 0: none.
  unsigned int climbed_hypotheses = 3;
  unsigned int climb_rounds = 2;
  /// Tilts tried when the two maps' up axes may disagree (each estimated from its own cameras, up_axis.h):
  /// around the `tilted_hypotheses` best refined hypotheses, rotations within ±tilt_range_deg about the two
  /// axes perpendicular to the up axis in tilt_step_deg steps, the one whose fine vote is fullest refined
  /// again. 0: none (maps sharing their up axis exactly, as two maps of one gravity-aligned SLAM).
  double tilt_range_deg = 0.0;
  double tilt_step_deg = 2.0;
  /// 6 since 2026-11-29 (3 before): with 5° rotations more refinements of one place compete, and the one whose tilt
  /// reached the truth fell to 5th or 6th place on maps 6° off gravity.
  unsigned int tilted_hypotheses = 6;
  /// The winner's final pass (the trimmed ICP on every source point) also starts from it tilted within
  /// ±final_tilt_range_deg about the two axes perpendicular to the up axis, in final_tilt_step_deg steps (25 starts by
  /// default, about the centroid of the winner's inliers: the part of the source that overlaps the target), and the
  /// finished pose with the highest inlier score is kept (a tie keeps the untilted start's). The tilts above are
  /// chosen by the fine vote's count in 2 cm cells, which cannot tell the truth from a pose 2° off at a fifth of
  /// overlap; the trimmed ICP comes back from about 0.5° only, and the score of where it ends tells the two apart
  /// (docs/global_alignment.md, "The final tilts"). Every search runs them, also the one about z that levelled maps
  /// try as well. 0: none; at most 10 steps each way.
  double final_tilt_range_deg = 4.0;
  double final_tilt_step_deg = 2.0;
  /// Rounds of the final tilts (1-10): while a round's winner is a tilted start that ended in another basin than the
  /// untilted start's (turned from it by a quarter of a tilt step or more), at most this many in all, the tilts are
  /// tried again about the winner and kept while its inlier score grows. A pose 6° off comes within 2° in one round, to
  /// the truth in the next (docs/global_alignment.md, "Rounds of final tilts"). 1: one round.
  unsigned int final_tilt_rounds = 3;
  /// A source much larger than the target is searched the other way, the target onto it, the result inverted
  /// (GlobalAlignmentResult::reversed): when that at least doubles the vote's sample pairs, the source's sample being
  /// capped lower (max_source_samples) than the target's (a whole map aligned onto one of its mini-maps: few of the
  /// whole map's samples lie where the mini-map is). false: always the caller's way.
  bool reverse_larger_source = true;
  /// Threads the rotations' votes, the hypotheses' refinement and the tilts are shared out on (0: every
  /// hardware thread, at most 1024); each writes only its own result, so the result does not depend on it.
  unsigned int threads = 0;
  /// Trimmed ICP: iterations per hypothesis and for the final, full-cloud pass.
  int hypothesis_iterations = 20;
  int final_iterations = 50;
  /// First distance limit of the trimmed ICP: refine() starts there (0: 2
  /// vote cells); align() starts at 2 fine cells, the fine vote's accuracy.
  double initial_distance = 0.0;
  /// Each iteration the limit becomes `shrink_factor` times the median residual
  /// of the pairs kept, never growing and never below `min_distance`
  /// (0: 2 target spacings). 1 lets only the closer half of the pairs pull, so
  /// parts without counterpart and the fringe of the overlap do not bias the
  /// result; a wider 3 was measured to leave the truth on partial overlaps of
  /// the real map (docs/global_alignment.md).
  double shrink_factor = 1.0;
  double min_distance = 0.0;
  /// A source point counts as an inlier when a target point is this close
  /// (0: 2 target spacings); hypotheses are ranked by inlier count.
  double inlier_distance = 0.0;
};

/// @brief What the search found.
struct GlobalAlignmentResult {
  /// Maps the source onto the target.
  Eigen::Matrix4d transformation = Eigen::Matrix4d::Identity();
  /// Fraction of source points with a target point within `inlier_distance`:
  /// an estimate of the overlap.
  double inlier_fraction = 0.0;
  std::size_t inliers = 0;
  /// The inliers' MSAC score: each counts 1 - (d / inlier_distance)^2, d its distance to the nearest target point.
  /// Hypotheses are ranked by it (since 2026-11-28; by the count before): of two poses with as many inliers, the
  /// tighter fit wins.
  double inlier_score = 0.0;
  /// The trimmed ICP's last distance limit and the median residual of its pairs.
  double distance_limit = 0.0;
  double median_residual = 0.0;
  /// The target spacing the derived lengths came from, and the lengths used.
  double target_spacing = 0.0;
  double inlier_distance = 0.0;
  std::size_t hypotheses_voted = 0;
  std::size_t hypotheses_refined = 0;
  /// Whether the search ran the other way, the target onto the source, its transformation inverted
  /// (GlobalAlignmentSettings::reverse_larger_source: a source much larger than the target). The inlier figures and
  /// the spacing are the caller's way (of the source's points, against the target); the distance limit and the median
  /// residual are the reversed trimmed ICP's.
  bool reversed = false;
  double time_ms = 0.0;
};

/// @brief Global registration of xyz clouds (finite points only are used).
/// Holds the target: its index and spacing are computed once in setTarget().
class GlobalAlignment {
 public:
  using Cloud = pcl::PointCloud<pcl::PointXYZ>;
  using Ptr = std::shared_ptr<GlobalAlignment>;
  using ConstPtr = std::shared_ptr<const GlobalAlignment>;

  /// @brief Checks the settings.
  /// @param settings  std::invalid_argument names the first one out of range
  explicit GlobalAlignment(GlobalAlignmentSettings settings = {});
  ~GlobalAlignment();
  GlobalAlignment(GlobalAlignment&&) noexcept;
  GlobalAlignment& operator=(GlobalAlignment&&) noexcept;

  /// @brief PCL-style class name, for messages.
  static std::string getClassName() { return "GlobalAlignment"; }
  /// @brief The settings given to the constructor.
  const GlobalAlignmentSettings& settings() const { return settings_; }

  /// @brief Sets the target and builds its search structures.
  /// @param target  at least 3 finite points, not all identical (else std::invalid_argument)
  void setTarget(const Cloud& target);
  /// @brief Finds the transformation taking `source` onto the target, from any rotation about the up axis
  /// and any translation; a source much larger than the target is searched the other way
  /// (GlobalAlignmentSettings::reverse_larger_source).
  /// @param source  at least 3 finite points (else std::invalid_argument); throws when no target is set
  /// @param source_up_axis  the source's own up axis when it differs from the settings' `up_axis` (a map
  ///        written in its first camera's frame): the source is first turned so that it becomes `up_axis`.
  ///        Zero (the default): the settings' `up_axis`
  GlobalAlignmentResult align(const Cloud& source,
                              const Eigen::Vector3d& source_up_axis = Eigen::Vector3d::Zero()) const;
  /// @brief As align(source, source_up_axis), about the given up axis and with the given tilts instead of the
  /// settings' `up_axis` and `tilt_range_deg`: one target, searched about several axes, is indexed once.
  /// @param source          as align()
  /// @param source_up_axis  as align()
  /// @param up_axis         the target's up axis (finite, non-zero)
  /// @param tilt_range_deg  as GlobalAlignmentSettings::tilt_range_deg (0-30, at most 20 tilt steps)
  GlobalAlignmentResult align(const Cloud& source, const Eigen::Vector3d& source_up_axis,
                              const Eigen::Vector3d& up_axis, double tilt_range_deg) const;

  /// @brief An aligner with other search settings sharing this one's target (its points, index and sample: not built
  /// again), as GlobalLandmarkAligner's first look at alternative levellings does.
  /// @param settings  checked as the constructor checks them; those that shape the target (`sample_cell`,
  ///                  `max_target_samples`, `fine_window`, `medium_cell`) must equal this aligner's (else
  ///                  std::invalid_argument naming the first that differs)
  GlobalAlignment withSearchSettings(GlobalAlignmentSettings settings) const;
  /// @brief Only the trimmed ICP (no search), from `guess`: for a start already in the basin.
  /// @param source  as align()
  /// @param guess   initial transformation of the source onto the target
  GlobalAlignmentResult refine(const Cloud& source, const Eigen::Matrix4d& guess) const;

  /// @brief The target's points, search index and spacing (opaque: defined in the source file).
  struct Target;

 private:
  /// The trimmed ICP on every source point from `start`, and the result's fields; the centroid of its inliers (source
  /// coordinates; zero when none) in `inlier_centroid` when given.
  GlobalAlignmentResult finish(const std::vector<Eigen::Vector3f>& source, const Eigen::Matrix4d& start,
                               double start_distance, Eigen::Vector3d* inlier_centroid = nullptr) const;
  /// finish() from `start` and from `start` tilted about `pivot` (source coordinates; the settings' final tilts,
  /// about the two axes perpendicular to `axis`), in parallel; the highest inlier score, a tie to the untilted start. A
  /// range of 0: finish() from `start` alone. Then the settings' further rounds (final_tilt_rounds) about the winner.
  GlobalAlignmentResult finishTilted(const std::vector<Eigen::Vector3f>& source, const Eigen::Matrix4d& start,
                                     double start_distance, const Eigen::Vector3d& axis,
                                     const Eigen::Vector3d& pivot) const;
  /// One round of finishTilted: the winner, its inliers' centroid (source coordinates), and whether it ended in
  /// another basin than the untilted start (turned from it by a quarter of a tilt step or more).
  struct TiltedFinish {
    GlobalAlignmentResult result;
    Eigen::Vector3d inlier_centroid;
    bool other_basin = false;
  };
  TiltedFinish finishTiltedOnce(const std::vector<Eigen::Vector3f>& source, const Eigen::Matrix4d& start,
                                double start_distance, const Eigen::Vector3d& axis, const Eigen::Vector3d& pivot) const;
  /// The search of align() on the finite `source` as given: levelled onto `up_axis`, the vote, the refined
  /// hypotheses, the climb, the tilts and the final pass (time_ms left to align()).
  GlobalAlignmentResult alignAsGiven(std::vector<Eigen::Vector3f> source, const Eigen::Vector3d& source_up_axis,
                                     const Eigen::Vector3d& up_axis, double tilt_range_deg) const;
  /// align() the other way: this target searched onto a GlobalAlignment whose target is `source`, the result
  /// inverted and its inlier figures counted the caller's way.
  GlobalAlignmentResult alignReversed(const std::vector<Eigen::Vector3f>& source, const Eigen::Vector3d& source_up_axis,
                                      const Eigen::Vector3d& up_axis, double tilt_range_deg) const;
  /// Threads for `n` independent jobs: the settings' count (0: every hardware thread), at most n.
  unsigned threadsFor(std::size_t n) const;

  GlobalAlignmentSettings settings_;
  /// Shared with the aligners withSearchSettings() makes; never changed once built (setTarget() replaces it).
  std::shared_ptr<const Target> target_;
  std::unique_ptr<WorkerPool> pool_;
};

}  // namespace weighted_icp
