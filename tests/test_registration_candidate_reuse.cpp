// Candidate reuse (CandidateCache) is exact: whole ICP runs are bit-identical with and without it, for any
// thread count, and a point that jumps beyond its margin is searched again.

#include <random>
#include <tuple>

#include <gtest/gtest.h>

#include <pcl/common/transforms.h>
#include <pcl/point_types.h>
#include <pcl/registration/correspondence_estimation.h>
#include <pcl/registration/icp.h>
#include "random_clouds.h"

#include "test_support.h"
#include "weighted_icp/io/map_format.h"
#include "weighted_icp/registration/landmark_point.h"
#include "weighted_icp/registration/rigid_motion.h"
#include "weighted_icp/registration/weight_strategies.h"
#include "weighted_icp/registration/weighted_correspondence_estimation.h"

namespace {

using namespace weighted_icp;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;
using Weighted = WeightedCorrespondenceEstimation<LandmarkPoint, LandmarkPoint, double>;
using WeightedXyz = WeightedCorrespondenceEstimation<pcl::PointXYZ, pcl::PointXYZ>;

struct IcpRun {
  Eigen::Matrix4d transformation;
  int iterations;
  double fitness;
};

class CountingIcp : public pcl::IterativeClosestPoint<LandmarkPoint, LandmarkPoint, double> {
 public:
  int iterations() const { return nr_iterations_; }
};

/// One whole ICP run with the weighted rule.
IcpRun runIcp(const LandmarkCloud::Ptr& source, const LandmarkCloud::Ptr& target, unsigned k, double max_distance,
              bool reciprocal, bool reuse, unsigned threads) {
  auto ce = std::make_shared<Weighted>(k);
  ce->setCandidateReuse(reuse);
  ce->setNumberOfThreads(threads);
  CountingIcp icp;
  icp.setCorrespondenceEstimation(ce);
  icp.setUseReciprocalCorrespondences(reciprocal);
  icp.setMaxCorrespondenceDistance(max_distance);
  icp.setMaximumIterations(40);
  icp.setInputSource(source);
  icp.setInputTarget(target);
  LandmarkCloud aligned;
  icp.align(aligned);
  return {icp.getFinalTransformation(), icp.iterations(), icp.getFitnessScore()};
}

void expectIdentical(const IcpRun& a, const IcpRun& b) {
  EXPECT_EQ(a.iterations, b.iterations);
  for (int i = 0; i < 16; ++i) ASSERT_EQ(a.transformation.data()[i], b.transformation.data()[i]) << "entry " << i;
  EXPECT_EQ(a.fitness, b.fitness);
}

TEST(CandidateReuse, WholeIcpRunsAreBitIdenticalToTheUncachedSearch) {
  WEIGHTED_ICP_REQUIRE_FILE(weighted_icp::testing::realMapPath());
  const LandmarkMap map = io::readLandmarkMap(weighted_icp::testing::realMapPath()).withMinObservations(2);
  auto [target_map, source_map] = map.alternateHalves();
  source_map.transform(Displacement{0.08, -0.05, 0.03, 2, -1, 8}.toIsometry());
  const std::vector<std::pair<const char*, WeightFunction>> strategies = {{"covariance", CovarianceWeight{}},
                                                                          {"observations", ObservationCountWeight{}}};
  int compared = 0;
  for (const auto& [name, weight] : strategies) {
    const auto target = toLandmarkCloud(target_map, weight);
    const auto source = toLandmarkCloud(source_map, weight);
    for (const unsigned k : {1u, 5u}) {
      for (const double max_distance : {std::sqrt(std::numeric_limits<double>::max()), 0.05}) {
        for (const bool reciprocal : {false, true}) {
          SCOPED_TRACE(::testing::Message()
                       << name << " k " << k << " max distance " << max_distance << (reciprocal ? " reciprocal" : ""));
          const IcpRun uncached = runIcp(source, target, k, max_distance, reciprocal, false, 1);
          expectIdentical(uncached, runIcp(source, target, k, max_distance, reciprocal, true, 1));
          expectIdentical(uncached, runIcp(source, target, k, max_distance, reciprocal, true, 2));
          EXPECT_GT(uncached.iterations, 3);  // long enough for candidates to be reused
          ++compared;
        }
      }
    }
  }
  EXPECT_EQ(compared, 16);
}

/// Random points with exact duplicates, so that distance ties (FLANN's order) occur.
Cloud::Ptr cloudWithDuplicates(std::size_t n, unsigned seed) {
  return weighted_icp::testing::randomCloud(n, seed, 1.0f, 10);
}

pcl::Correspondences correspondencesOf(
    pcl::registration::CorrespondenceEstimationBase<pcl::PointXYZ, pcl::PointXYZ>& ce, const Cloud::Ptr& source) {
  ce.setInputSource(source);
  pcl::Correspondences out;
  ce.determineCorrespondences(out);
  return out;
}

void expectSame(const pcl::Correspondences& a, const pcl::Correspondences& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].index_query, b[i].index_query) << "at " << i;
    ASSERT_EQ(a[i].index_match, b[i].index_match) << "at " << i;
    ASSERT_EQ(a[i].distance, b[i].distance) << "at " << i;
  }
}

TEST(CandidateReuse, ReusedCandidatesKeepPclsAnswerWithTiesAndAJumpIsSearchedAgain) {
  const auto target = cloudWithDuplicates(3000, 3);
  auto source = cloudWithDuplicates(2000, 4);  // its duplicates tie with each other's targets too
  for (std::size_t i = 0; i < 300; ++i) source->push_back((*target)[i * 3]);  // exact ties at distance 0
  for (const unsigned k : {1u, 5u}) {
    SCOPED_TRACE(::testing::Message() << "k " << k);
    WeightedXyz cached(k);
    cached.setInputTarget(target);
    if (k > 1) cached.setTargetWeights(std::vector<double>(target->size(), 1.0));  // uniform: PCL's choice
    pcl::registration::CorrespondenceEstimation<pcl::PointXYZ, pcl::PointXYZ> stock;
    stock.setInputTarget(target);

    expectSame(correspondencesOf(stock, source), correspondencesOf(cached, source));
    EXPECT_EQ(cached.getLastSearchedCount(), source->size());

    // A small motion: every point stays within its margin, and PCL's answer is kept.
    auto nudged = std::make_shared<Cloud>();
    pcl::transformPointCloud(*source, *nudged,
                             Displacement{1e-4, 0, 0, 0, 0, 0.01}.toIsometry().matrix().cast<float>());
    expectSame(correspondencesOf(stock, nudged), correspondencesOf(cached, nudged));
    EXPECT_GT(cached.getLastReusedCount(), source->size() * 9 / 10);

    // The same positions again: only slots that keep no candidates (a crowd of ties) are searched.
    correspondencesOf(cached, nudged);
    const std::size_t always_searched = cached.getLastSearchedCount();
    EXPECT_EQ(cached.getLastReusedCount() + always_searched, source->size());

    // One point jumps far beyond its margin: it alone is searched again, and still answered exactly.
    auto jumped = std::make_shared<Cloud>(*nudged);
    (*jumped)[17].x += 0.7f;
    const auto after_jump = correspondencesOf(cached, jumped);
    EXPECT_EQ(cached.getLastSearchedCount(), always_searched + 1);
    expectSame(correspondencesOf(stock, jumped), after_jump);
  }
}

TEST(CandidateReuse, ManySmallStepsAreAnsweredFromTheRememberedNearestAsTheTreeAnswers) {
  // Late ICP: every point moves a little per call. Most calls are answered from the remembered k + 1
  // nearest (no ranking of all candidates); neighbours whose order swaps on the way must not be missed.
  // Random weights make the choice depend on all k neighbours and their order.
  const auto target = cloudWithDuplicates(3000, 5);
  auto source = cloudWithDuplicates(2000, 6);
  for (std::size_t i = 0; i < 200; ++i) source->push_back((*target)[i * 7]);  // ties at distance 0
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> level(0, 3);  // few levels: equal weights go to the nearer point
  std::vector<double> weights(target->size());
  for (auto& w : weights) w = level(rng);
  WeightedXyz cached(5), uncached(5);
  for (WeightedXyz* ce : {&cached, &uncached}) {
    ce->setInputTarget(target);
    ce->setTargetWeights(weights);
  }
  uncached.setCandidateReuse(false);
  auto moved = std::make_shared<Cloud>();
  std::size_t reused = 0, queries = 0;
  for (int step = 0; step < 16; ++step) {
    SCOPED_TRACE(::testing::Message() << "step " << step);
    const double s = 1.0 - step / 32.0;  // steps shrink, as ICP's do (point spacing ~0.13, steps ~1 cm)
    pcl::transformPointCloud(*source, *moved,
                             Displacement{0.01 * step * s, -0.006 * step, 0.004 * step, 0.3 * step * s, 0, 0.5 * step}
                                 .toIsometry()
                                 .matrix()
                                 .cast<float>());
    expectSame(correspondencesOf(uncached, moved), correspondencesOf(cached, moved));
    if (step > 0) {
      reused += cached.getLastReusedCount();
      queries += moved->size();
    }
  }
  EXPECT_GT(reused, queries / 2);

  // Fewer neighbours on the same object (refinement's k = 1), then more than it was sized for.
  for (const unsigned k : {1u, 8u}) {
    SCOPED_TRACE(::testing::Message() << "k " << k);
    cached.setNumberOfNeighbors(k);
    uncached.setNumberOfNeighbors(k);
    expectSame(correspondencesOf(uncached, moved), correspondencesOf(cached, moved));
    expectSame(correspondencesOf(uncached, moved), correspondencesOf(cached, moved));
    EXPECT_GT(cached.getLastReusedCount(), moved->size() * 9 / 10);
  }
}

}  // namespace
