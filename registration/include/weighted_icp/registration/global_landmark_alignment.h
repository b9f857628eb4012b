#pragma once
// Landmark maps aligned from any start: GlobalAlignment finds the pose from
// geometry alone, then the paper's weighted ICP with its refinement stage
// finishes, its correspondence distance limited to what the global stage's
// residuals say, so landmarks with no counterpart in the other map (partial
// overlap) stay out of it.

#include <chrono>
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "weighted_icp/registration/global_alignment.h"
#include "weighted_icp/registration/landmark_alignment.h"
#include "weighted_icp/registration/landmark_point.h"
#include "weighted_icp/registration/up_axis.h"

namespace weighted_icp {

/// @brief Both stages' results.
struct GlobalLandmarkAlignmentResult {
  /// The final (weighted ICP) stage: its transformation maps the source as
  /// given onto the target; time_ms covers both stages. When the search ran
  /// the other way (global.reversed: a source much larger than the target) so
  /// did this stage, the target onto the source weighted by the source's
  /// weights, its transformation inverted: its fitness score, correspondences
  /// and degeneracy are then of the target's points.
  AlignmentResult alignment;
  /// The global stage alone.
  GlobalAlignmentResult global;
  /// The up axes of the search kept (the source's, the target's).
  Eigen::Vector3d source_up_axis = Eigen::Vector3d::UnitZ(), target_up_axis = Eigen::Vector3d::UnitZ();
  /// Alternatives (SharedUpAxes::alternatives) first looked at and, of them, searched fully
  /// (kAlternativesSearchedFully); the maps' own levelling and z are always searched. align(source): none.
  std::size_t first_looks = 0;
  std::size_t alternatives_searched = 0;
};

/// @brief Of SharedUpAxes::alternatives, how many GlobalLandmarkAligner::align(source, axes) searches fully at least.
/// When there are more, each is first looked at cheaply (the vote and its three best-voted hypotheses refined; no
/// climb, tilts or final tilts: about a fifth of a search), and only the ones whose look scores highest (these two,
/// and any scoring kFirstLookKeptFraction of the best look or more) are searched as the maps' own levellings are
/// (docs/global_alignment.md, "A first look at the pitched levellings").
inline constexpr std::size_t kAlternativesSearchedFully = 2;
/// @brief Further alternatives searched fully: every one whose first look scores at least this fraction of the best
/// look's. A look ranks levellings well where the map holds enough landmarks for the right one to stand out (fr3's
/// mini-maps: 149 against 40-60), not on a mini-map of 99 landmarks, where every look scores 7-15 and the right
/// levelling's may come last (9.4 against the best 13.6); there a half keeps nearly all.
inline constexpr double kFirstLookKeptFraction = 0.5;

/// @brief PCL-style aligner of weighted landmark clouds from any start.
class GlobalLandmarkAligner {
 public:
  using Ptr = std::shared_ptr<GlobalLandmarkAligner>;
  using ConstPtr = std::shared_ptr<const GlobalLandmarkAligner>;

  /// @brief Checks both stages' settings (std::invalid_argument names the one out of range).
  /// @param global  the search's settings
  /// @param icp     the final weighted ICP's; its refinement stage always runs, and its distance limit
  ///                is the smaller of its own and the global stage's final one
  explicit GlobalLandmarkAligner(GlobalAlignmentSettings global = {}, AlignmentSettings icp = {});

  /// @brief PCL-style class name, for messages.
  static std::string getClassName() { return "GlobalLandmarkAligner"; }

  /// @brief Sets the target of both stages.
  /// @param target  as LandmarkAligner::setTarget() and GlobalAlignment::setTarget() require
  void setTarget(LandmarkCloud::ConstPtr target);
  /// @brief Aligns `source` onto the target from any rotation about the up axis and any translation.
  /// @param source  as LandmarkAligner::align() requires; a degenerate problem is reported in the result. Its
  ///                weights serve when it is much larger than the target: both stages then run the other way, the
  ///                target onto it (GlobalAlignmentSettings::reverse_larger_source)
  GlobalLandmarkAlignmentResult align(const LandmarkCloud::ConstPtr& source);
  /// @brief As align(source), the search about the given up axes (chooseUpAxes(): each map levelled by its own,
  /// with tilts, then those of `axes.alternatives` a first look scores highest (kAlternativesSearchedFully), and z
  /// tried as well when `axes.also_try_z`; the search with the highest inlier score kept, ties to the earlier but
  /// z's; the time reported is all the searches' and looks').
  /// @param source  as align(source)
  /// @param axes    the source's and the target's up axes; the settings' up_axis and tilt_range_deg give way
  GlobalLandmarkAlignmentResult align(const LandmarkCloud::ConstPtr& source, const SharedUpAxes& axes);

 private:
  /// Which of `axes.alternatives` to search fully (`indices`, in their order): all when there are at most
  /// kAlternativesSearchedFully, else those whose first look (screen_) scores highest (ties to the earlier) and those
  /// scoring kFirstLookKeptFraction of the best look or more; how many were looked at and the looks' time.
  struct Promising {
    std::vector<std::size_t> indices;
    std::size_t looks = 0;
    double time_ms = 0.0;
  };
  Promising promisingAlternatives(const GlobalAlignment::Cloud& source, const SharedUpAxes& axes);
  /// The weighted ICP from the global stage's result, within its distance limit.
  GlobalLandmarkAlignmentResult finish(const LandmarkCloud::ConstPtr& source, GlobalAlignmentResult global,
                                       std::chrono::steady_clock::time_point start) const;

  GlobalAlignment global_;
  /// The first look at alternative levellings: global_'s settings with the three best-voted hypotheses refined, no
  /// climb or tilts and 20 final iterations; it shares global_'s target (GlobalAlignment::withSearchSettings).
  GlobalAlignment screen_;
  AlignmentSettings icp_settings_;
  LandmarkCloud::ConstPtr target_;
};

}  // namespace weighted_icp
