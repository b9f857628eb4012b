#include "weighted_icp/registration/landmark_alignment.h"

#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

#include <pcl/registration/icp.h>
#include <pcl/search/kdtree.h>

#include "weighted_icp/registration/weighted_correspondence_estimation.h"

namespace weighted_icp {

namespace {

using Icp = pcl::IterativeClosestPoint<LandmarkPoint, LandmarkPoint, double>;
using Correspondence = WeightedCorrespondenceEstimation<LandmarkPoint, LandmarkPoint, double>;

/// PCL keeps the iteration count and the last correspondences protected.
class InspectableIcp : public Icp {
 public:
  int iterations() const { return nr_iterations_; }
  std::size_t lastCorrespondenceCount() const { return correspondences_ ? correspondences_->size() : 0; }
};

void requireFinitePoint(const LandmarkCloud::ConstPtr& cloud, const char* what) {
  if (!cloud || cloud->empty()) throw std::invalid_argument(std::string(what) + " cloud is empty");
  for (const auto& p : *cloud)
    if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) return;
  throw std::invalid_argument(std::string(what) + " cloud has no finite point");
}

}  // namespace

struct LandmarkAligner::Pipeline {
  InspectableIcp icp;
  Correspondence::Ptr weighted;
  Correspondence::Ptr nearest;
  pcl::search::KdTree<LandmarkPoint>::Ptr target_tree{new pcl::search::KdTree<LandmarkPoint>};
  bool has_target = false;
};

LandmarkAligner::LandmarkAligner(AlignmentSettings settings)
    : settings_(settings), pipeline_(std::make_unique<Pipeline>()) {
  if (settings_.k == 0) throw std::invalid_argument("AlignmentSettings::k must be >= 1");
  if (settings_.max_iterations < 1 || settings_.refine_max_iterations < 1)
    throw std::invalid_argument("AlignmentSettings: iteration limits must be >= 1");
  if (!(settings_.max_correspondence_distance > 0.0))
    throw std::invalid_argument("AlignmentSettings::max_correspondence_distance must be > 0");
  pipeline_->weighted = std::make_shared<Correspondence>(settings_.k);
  pipeline_->nearest = std::make_shared<Correspondence>(1);
  for (const auto& ce : {pipeline_->weighted, pipeline_->nearest}) ce->setNumberOfThreads(settings_.threads);
  Icp& icp = pipeline_->icp;
  icp.setMaxCorrespondenceDistance(settings_.max_correspondence_distance);
  icp.setTransformationEpsilon(settings_.transformation_epsilon);
  icp.setEuclideanFitnessEpsilon(settings_.euclidean_fitness_epsilon);
}

LandmarkAligner::~LandmarkAligner() = default;
LandmarkAligner::LandmarkAligner(LandmarkAligner&&) noexcept = default;
LandmarkAligner& LandmarkAligner::operator=(LandmarkAligner&&) noexcept = default;

void LandmarkAligner::setTarget(LandmarkCloud::ConstPtr target) {
  requireFinitePoint(target, "target");
  pipeline_->target_tree->setInputCloud(target);
  pipeline_->icp.setInputTarget(target);
  // The tree serves getFitnessScore(); force_no_recompute keeps ICP from
  // rebuilding it on every align(). Our correspondence estimation keeps its own.
  pipeline_->icp.setSearchMethodTarget(pipeline_->target_tree, true);
  pipeline_->has_target = true;
}

AlignmentResult LandmarkAligner::align(const LandmarkCloud::ConstPtr& source, const Eigen::Matrix4d& guess) {
  if (!pipeline_->has_target) throw std::invalid_argument("LandmarkAligner::align: no target set");
  requireFinitePoint(source, "source");
  InspectableIcp& icp = pipeline_->icp;
  icp.setInputSource(source);
  LandmarkCloud aligned;
  AlignmentResult result;

  const auto start = std::chrono::steady_clock::now();
  icp.setCorrespondenceEstimation(pipeline_->weighted);
  icp.setMaximumIterations(settings_.max_iterations);
  icp.align(aligned, guess);
  result.iterations = icp.iterations();
  if (settings_.refine) {
    icp.setCorrespondenceEstimation(pipeline_->nearest);
    icp.setMaximumIterations(settings_.refine_max_iterations);
    icp.align(aligned, icp.getFinalTransformation());
    result.refine_iterations = icp.iterations();
  }
  result.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();

  result.transformation = icp.getFinalTransformation();
  result.converged = icp.hasConverged();
  result.correspondences = icp.lastCorrespondenceCount();
  result.fitness_score = icp.getFitnessScore();
  return result;
}

AlignmentResult alignLandmarkMaps(const LandmarkMap& source, const LandmarkMap& target, const WeightFunction& weight,
                                  const AlignmentSettings& settings, const Eigen::Matrix4d& guess) {
  LandmarkAligner aligner(settings);
  aligner.setTarget(toLandmarkCloud(target, weight));
  return aligner.align(toLandmarkCloud(source, weight), guess);
}

}  // namespace weighted_icp
