// GlobalLandmarkAligner: the global search, then the weighted ICP within its distance limit.
#include "weighted_icp/registration/global_landmark_alignment.h"

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <utility>

#include <pcl/common/io.h>

namespace weighted_icp {

GlobalLandmarkAligner::GlobalLandmarkAligner(GlobalAlignmentSettings global, AlignmentSettings icp)
    : global_(std::move(global)), icp_settings_(icp) {
  icp_settings_.refine = true;
  LandmarkAligner check(icp_settings_);  // throws on settings out of range
}

void GlobalLandmarkAligner::setTarget(LandmarkCloud::ConstPtr target) {
  if (!target || target->empty()) throw std::invalid_argument("GlobalLandmarkAligner: target cloud is empty");
  GlobalAlignment::Cloud xyz;
  pcl::copyPointCloud(*target, xyz);
  global_.setTarget(xyz);
  target_ = std::move(target);
  target_xyz_ = std::move(xyz);
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
  // The search about `up` with tilts within ±tilt: the one set up by setTarget() when it is that one.
  const auto search = [&](const Eigen::Vector3d& source_up, const Eigen::Vector3d& up, double tilt) {
    const GlobalAlignmentSettings& own = global_.settings();
    if (source_up == up && up == own.up_axis && tilt == own.tilt_range_deg) return global_.align(xyz);
    GlobalAlignmentSettings settings = own;
    settings.up_axis = up;
    settings.tilt_range_deg = tilt;
    GlobalAlignment other(settings);
    other.setTarget(target_xyz_);
    return other.align(xyz, source_up);
  };
  GlobalAlignmentResult best = search(axes.source, axes.target, axes.tilt_range_deg);
  Eigen::Vector3d source_up = axes.source, target_up = axes.target;
  if (axes.also_try_z) {
    GlobalAlignmentResult z = search(Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitZ(), 0.0);
    // A tie keeps the maps' own z, as before the axes were estimated. No margin in its favour: on a sparse map
    // a pose tens of degrees off can leave nearly as many inliers as the truth (fr3's, overlap 0.2).
    if (z.inliers >= best.inliers) {
      z.time_ms += best.time_ms;
      best = z, source_up = target_up = Eigen::Vector3d::UnitZ();
    } else {
      best.time_ms += z.time_ms;
    }
  }
  GlobalLandmarkAlignmentResult result = finish(source, best, start);
  result.source_up_axis = source_up, result.target_up_axis = target_up;
  return result;
}

GlobalLandmarkAlignmentResult GlobalLandmarkAligner::finish(const LandmarkCloud::ConstPtr& source,
                                                            GlobalAlignmentResult global,
                                                            std::chrono::steady_clock::time_point start) const {
  GlobalLandmarkAlignmentResult result;
  result.global = std::move(global);
  AlignmentSettings icp = icp_settings_;
  icp.max_correspondence_distance = std::min(icp.max_correspondence_distance, result.global.distance_limit);
  LandmarkAligner aligner(icp);
  aligner.setTarget(target_);
  result.alignment = aligner.align(source, result.global.transformation);
  result.alignment.time_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace weighted_icp
