#include "weighted_icp/registration/landmark_alignment.h"

#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/Eigenvalues>

#include <pcl/registration/icp.h>
#include <pcl/search/kdtree.h>

#include "weighted_icp/registration/correspondence_repeat_criteria.h"
#include "weighted_icp/registration/weighted_correspondence_estimation.h"

namespace weighted_icp {

namespace {

using Icp = pcl::IterativeClosestPoint<LandmarkPoint, LandmarkPoint, double>;
using Correspondence = WeightedCorrespondenceEstimation<LandmarkPoint, LandmarkPoint, double>;

/// PCL keeps the iteration count and the last correspondences protected.
class InspectableIcp : public Icp {
 public:
  InspectableIcp() {
    criteria_ =
        std::make_shared<CorrespondenceRepeatCriteria<double>>(nr_iterations_, transformation_, *correspondences_);
    convergence_criteria_ = criteria_;
  }
  CorrespondenceRepeatCriteria<double>& criteria() { return *criteria_; }
  int iterations() const { return nr_iterations_; }
  std::size_t lastCorrespondenceCount() const { return correspondences_ ? correspondences_->size() : 0; }

 private:
  CorrespondenceRepeatCriteria<double>::Ptr criteria_;
};

/// Checks what every cloud given to the aligner needs; returns its finite point count.
std::size_t requireUsableCloud(const LandmarkCloud::ConstPtr& cloud, const char* what) {
  if (!cloud || cloud->empty()) throw std::invalid_argument(std::string(what) + " cloud is empty");
  NearestNeighborIndex::requireIndexable(*cloud, std::string(what));
  std::size_t finite = 0;
  for (const auto& p : *cloud)
    if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) ++finite;
  if (finite == 0) throw std::invalid_argument(std::string(what) + " cloud has no finite point");
  return finite;
}

/// Why the finite points of `cloud` cannot fix a rigid motion (empty when
/// they can): fewer than 3, all identical, or all on one line.
std::string shapeDegeneracy(const LandmarkCloud& cloud, std::size_t finite, const char* what) {
  const std::string points = std::to_string(finite) + " finite " + what + " points";
  if (finite < 3) return "only " + points + ", fewer than 3";
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const auto& p : cloud)
    if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) sum += Eigen::Vector3d(p.x, p.y, p.z);
  const Eigen::Vector3d mean = sum / static_cast<double>(finite);
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const auto& p : cloud) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    const Eigen::Vector3d d = Eigen::Vector3d(p.x, p.y, p.z) - mean;
    scatter += d * d.transpose();
  }
  const Eigen::Vector3d spread = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(scatter).eigenvalues();  // ascending
  if (!(spread[2] > 0.0)) return "all " + points + " are identical";
  // Float coordinates of points on a line scatter off it by ~1e-7 relative,
  // 1e-14 in these squared terms; any real map is many orders above 1e-10.
  if (spread[1] <= 1e-10 * spread[2]) return "all " + points + " are collinear";
  return {};
}

}  // namespace

struct LandmarkAligner::Pipeline {
  InspectableIcp icp;
  Correspondence::Ptr weighted;  // k = settings.k; k = 1 during refinement
  pcl::search::KdTree<LandmarkPoint>::Ptr target_tree{new pcl::search::KdTree<LandmarkPoint>};
  bool has_target = false;
  std::size_t target_points = 0;  // finite ones
  std::string target_degeneracy;  // shapeDegeneracy() of the target, found once
};

LandmarkAligner::LandmarkAligner(AlignmentSettings settings)
    : settings_(settings), pipeline_(std::make_unique<Pipeline>()) {
  if (settings_.k == 0) throw std::invalid_argument("AlignmentSettings::k must be >= 1");
  if (settings_.threads > Correspondence::kMaxThreads)
    throw std::invalid_argument("AlignmentSettings::threads must be at most " +
                                std::to_string(Correspondence::kMaxThreads) + " (got " +
                                std::to_string(settings_.threads) + ")");
  if (settings_.max_iterations < 1 || settings_.refine_max_iterations < 1)
    throw std::invalid_argument("AlignmentSettings: iteration limits must be >= 1");
  if (!(settings_.max_correspondence_distance > 0.0))
    throw std::invalid_argument("AlignmentSettings::max_correspondence_distance must be > 0");
  pipeline_->weighted = std::make_shared<Correspondence>(settings_.k);
  pipeline_->weighted->setNumberOfThreads(settings_.threads);
  InspectableIcp& icp = pipeline_->icp;
  icp.setMaxCorrespondenceDistance(settings_.max_correspondence_distance);
  icp.setTransformationEpsilon(settings_.transformation_epsilon);
  icp.setEuclideanFitnessEpsilon(settings_.euclidean_fitness_epsilon);
  icp.criteria().setStopOnRepeat(settings_.stop_on_repeated_correspondences);
}

LandmarkAligner::~LandmarkAligner() = default;

std::string LandmarkAligner::degeneracy(const LandmarkCloud& source, std::size_t source_points) const {
  if (!pipeline_->target_degeneracy.empty()) return pipeline_->target_degeneracy;
  const std::size_t target_points = pipeline_->target_points;
  // With k >= the target every source point picks the target's heaviest point
  // in range: ICP then pulls the whole source onto one point.
  if (settings_.k > 1 && settings_.k >= target_points)
    return "k = " + std::to_string(settings_.k) + " is at least the " + std::to_string(target_points) +
           " finite target points: every source point would choose among the whole target";
  return shapeDegeneracy(source, source_points, "source");
}

LandmarkAligner::LandmarkAligner(LandmarkAligner&&) noexcept = default;
LandmarkAligner& LandmarkAligner::operator=(LandmarkAligner&&) noexcept = default;

void LandmarkAligner::setTarget(LandmarkCloud::ConstPtr target) {
  // Before any tree is built: PCL's kd-tree overflows on the same points as ours.
  const std::size_t finite = requireUsableCloud(target, "target");
  pipeline_->target_points = finite;
  pipeline_->target_degeneracy = shapeDegeneracy(*target, finite, "target");
  pipeline_->target_tree->setInputCloud(target);
  pipeline_->icp.setInputTarget(target);
  // The tree serves getFitnessScore(); force_no_recompute keeps ICP from
  // rebuilding it on every align(). Our correspondence estimation keeps its own.
  pipeline_->icp.setSearchMethodTarget(pipeline_->target_tree, true);
  pipeline_->has_target = true;
}

AlignmentResult LandmarkAligner::align(const LandmarkCloud::ConstPtr& source, const Eigen::Matrix4d& guess) {
  if (!pipeline_->has_target) throw std::invalid_argument("LandmarkAligner::align: no target set");
  const std::size_t source_points = requireUsableCloud(source, "source");
  AlignmentResult result;
  result.reason = degeneracy(*source, source_points);
  if (!result.reason.empty()) {
    result.degenerate = true;
    result.transformation = guess;
    result.fitness_score = std::numeric_limits<double>::quiet_NaN();
    return result;
  }
  InspectableIcp& icp = pipeline_->icp;
  icp.setInputSource(source);
  LandmarkCloud aligned;

  const auto start = std::chrono::steady_clock::now();
  icp.setCorrespondenceEstimation(pipeline_->weighted);
  icp.setMaximumIterations(settings_.max_iterations);
  icp.align(aligned, guess);
  result.iterations = icp.iterations();
  if (settings_.refine) {
    // The same estimation with k = 1 (the nearest, whatever the weights): the candidates it gathered for
    // k + 1 neighbours hold the 2 nearest too, so refinement starts from them instead of searching again.
    Correspondence& ce = *pipeline_->weighted;
    ce.setNumberOfNeighbors(1);
    // The pose is the optimum of the weighted stage's last pairs: if k = 1 finds the same, stop at once.
    icp.criteria().carryOverToNextRun();
    icp.setMaximumIterations(settings_.refine_max_iterations);
    try {
      icp.align(aligned, icp.getFinalTransformation());
    } catch (...) {
      ce.setNumberOfNeighbors(settings_.k);
      throw;
    }
    ce.setNumberOfNeighbors(settings_.k);
    result.refine_iterations = icp.iterations();
  }
  result.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();

  result.transformation = icp.getFinalTransformation();
  result.converged = icp.hasConverged();
  result.stopped_at_iteration_limit =
      icp.criteria().getConvergenceState() ==
      pcl::registration::DefaultConvergenceCriteria<double>::CONVERGENCE_CRITERIA_ITERATIONS;
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
