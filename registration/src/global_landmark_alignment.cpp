// GlobalLandmarkAligner: the global search, then the weighted ICP within its distance limit (both the other way for a
// source much larger than the target).
#include "weighted_icp/registration/global_landmark_alignment.h"

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <utility>

#include <pcl/common/io.h>

#include "weighted_icp/registration/rigid_motion.h"

namespace weighted_icp {
namespace {

/// The first look's settings (GlobalLandmarkAligner::screen_): the vote and its best few hypotheses refined, no more.
/// Search settings only: the first look shares the full search's target (GlobalAlignment::withSearchSettings).
GlobalAlignmentSettings firstLookSettings(GlobalAlignmentSettings settings) {
  settings.refined_hypotheses = std::min(settings.refined_hypotheses, 3u);
  settings.climbed_hypotheses = 0;
  settings.tilt_range_deg = 0.0;
  settings.final_tilt_range_deg = 0.0;
  settings.final_iterations = std::min(settings.final_iterations, 20);
  return settings;
}

}  // namespace

GlobalLandmarkAligner::GlobalLandmarkAligner(GlobalAlignmentSettings global, AlignmentSettings icp)
    : global_(global), screen_(firstLookSettings(std::move(global))), icp_settings_(icp) {
  icp_settings_.refine = true;
  LandmarkAligner check(icp_settings_);  // throws on settings out of range
}

void GlobalLandmarkAligner::setTarget(LandmarkCloud::ConstPtr target) {
  if (!target || target->empty()) throw std::invalid_argument("GlobalLandmarkAligner: target cloud is empty");
  GlobalAlignment::Cloud xyz;
  pcl::copyPointCloud(*target, xyz);
  global_.setTarget(xyz);
  screen_ = global_.withSearchSettings(screen_.settings());
  target_ = std::move(target);
}

GlobalLandmarkAlignmentResult GlobalLandmarkAligner::align(const LandmarkCloud::ConstPtr& source) {
  if (!target_) throw std::invalid_argument("GlobalLandmarkAligner::align: no target set");
  if (!source || source->empty()) throw std::invalid_argument("GlobalLandmarkAligner: source cloud is empty");
  const auto start = std::chrono::steady_clock::now();
  GlobalAlignment::Cloud xyz;
  pcl::copyPointCloud(*source, xyz);
  return finish(source, global_.align(xyz), start);
}

GlobalLandmarkAlignmentResult GlobalLandmarkAligner::align(const LandmarkCloud::ConstPtr& source,
                                                           const SharedUpAxes& axes) {
  if (!target_) throw std::invalid_argument("GlobalLandmarkAligner::align: no target set");
  if (!source || source->empty()) throw std::invalid_argument("GlobalLandmarkAligner: source cloud is empty");
  const auto start = std::chrono::steady_clock::now();
  GlobalAlignment::Cloud xyz;
  pcl::copyPointCloud(*source, xyz);
  GlobalAlignmentResult best = global_.align(xyz, axes.source, axes.target, axes.tilt_range_deg);
  Eigen::Vector3d source_up = axes.source, target_up = axes.target;
  // One more search, kept when it scores higher (or as high, given `wins_ties`); the time is all the searches'.
  const auto tryAxes = [&](const Eigen::Vector3d& source_axis, const Eigen::Vector3d& target_axis,
                           double tilt_range_deg, bool wins_ties) {
    GlobalAlignmentResult other = global_.align(xyz, source_axis, target_axis, tilt_range_deg);
    const double time_ms = best.time_ms + other.time_ms;
    if (other.inlier_score > best.inlier_score || (wins_ties && other.inlier_score == best.inlier_score))
      best = std::move(other), source_up = source_axis, target_up = target_axis;
    best.time_ms = time_ms;
  };
  const Promising promising = promisingAlternatives(xyz, axes);
  for (const std::size_t i : promising.indices)
    tryAxes(axes.alternatives[i].first, axes.alternatives[i].second, axes.tilt_range_deg, false);
  best.time_ms += promising.time_ms;
  // A tie keeps the maps' own z, as before the axes were estimated. No margin in its favour: on a sparse map a pose
  // tens of degrees off can leave nearly as many inliers as the truth (fr3's, overlap 0.2).
  if (axes.also_try_z) tryAxes(Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitZ(), 0.0, true);
  GlobalLandmarkAlignmentResult result = finish(source, best, start);
  result.source_up_axis = source_up, result.target_up_axis = target_up;
  result.first_looks = promising.looks;
  result.alternatives_searched = promising.indices.size();
  return result;
}

GlobalLandmarkAligner::Promising GlobalLandmarkAligner::promisingAlternatives(const GlobalAlignment::Cloud& source,
                                                                              const SharedUpAxes& axes) {
  Promising promising;
  std::vector<std::size_t>& order = promising.indices;
  order.resize(axes.alternatives.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  if (order.size() <= kAlternativesSearchedFully) return promising;
  std::vector<double> scores(order.size());
  for (std::size_t i = 0; i < order.size(); ++i) {
    const GlobalAlignmentResult look =
        screen_.align(source, axes.alternatives[i].first, axes.alternatives[i].second, 0.0);
    scores[i] = look.inlier_score;
    promising.time_ms += look.time_ms;
  }
  promising.looks = order.size();
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return scores[a] > scores[b]; });
  // Past the best few, every look scoring kFirstLookKeptFraction of the best or more: on a small map the looks cannot
  // tell the levellings apart (all near the noise), and nearly all are then searched.
  const double kept_from = kFirstLookKeptFraction * scores[order.front()];
  std::size_t kept = kAlternativesSearchedFully;
  while (kept < order.size() && scores[order[kept]] >= kept_from) ++kept;
  order.resize(kept);
  std::sort(order.begin(), order.end());
  return promising;
}

GlobalLandmarkAlignmentResult GlobalLandmarkAligner::finish(const LandmarkCloud::ConstPtr& source,
                                                            GlobalAlignmentResult global,
                                                            std::chrono::steady_clock::time_point start) const {
  GlobalLandmarkAlignmentResult result;
  result.global = std::move(global);
  AlignmentSettings icp = icp_settings_;
  icp.max_correspondence_distance = std::min(icp.max_correspondence_distance, result.global.distance_limit);
  LandmarkAligner aligner(icp);
  if (result.global.reversed) {
    // As the search did: the target onto the source (its points the better ones to seek counterparts), inverted.
    aligner.setTarget(source);
    result.alignment = aligner.align(target_, inverseRigid(result.global.transformation));
    result.alignment.transformation = inverseRigid(result.alignment.transformation);
  } else {
    aligner.setTarget(target_);
    result.alignment = aligner.align(source, result.global.transformation);
  }
  result.alignment.time_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace weighted_icp
