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
}

GlobalLandmarkAlignmentResult GlobalLandmarkAligner::align(const LandmarkCloud::ConstPtr& source,
                                                           const Eigen::Vector3d& source_up_axis) {
  if (!target_) throw std::invalid_argument("GlobalLandmarkAligner::align: no target set");
  if (!source || source->empty()) throw std::invalid_argument("GlobalLandmarkAligner: source cloud is empty");
  const auto start = std::chrono::steady_clock::now();
  GlobalAlignment::Cloud xyz;
  pcl::copyPointCloud(*source, xyz);
  GlobalLandmarkAlignmentResult result;
  result.global = global_.align(xyz, source_up_axis);

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
