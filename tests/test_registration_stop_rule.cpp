// The "correspondences repeat" stop rule (CorrespondenceRepeatCriteria): it stops exactly when the pairs
// repeat, and on the real map it ends where the run without it ends, in fewer iterations.

#include <gtest/gtest.h>

#include "test_support.h"
#include "weighted_icp/io/map_format.h"
#include "weighted_icp/registration/correspondence_repeat_criteria.h"
#include "weighted_icp/registration/landmark_alignment.h"
#include "weighted_icp/registration/rigid_motion.h"

namespace {

using namespace weighted_icp;
using Criteria = CorrespondenceRepeatCriteria<double>;

/// The members an ICP would hold, watched by a criterion, with an increment no PCL test calls converged.
struct Watched {
  int iterations = 0;
  Eigen::Matrix4d increment = Eigen::Matrix4d::Identity();
  pcl::Correspondences pairs{{0, 3, 0.5f}, {1, 4, 0.25f}, {2, 5, 0.125f}};
  Criteria criteria{iterations, increment, pairs};
  Watched() {
    increment(0, 3) = 0.1;
    criteria.setAbsoluteMSE(-1.0);
    criteria.setRelativeMSE(-1.0);
  }
  /// One ICP iteration's end: the counter moves on and the criterion is asked.
  bool iterate() {
    ++iterations;
    return criteria.hasConverged();
  }
};

TEST(StopRule, StopsExactlyWhenThePairsRepeat) {
  Watched w;
  EXPECT_FALSE(w.iterate());  // nothing to compare with yet
  w.pairs[1].index_match = 6;
  EXPECT_FALSE(w.iterate());  // one pair changed
  EXPECT_FALSE(w.criteria.stoppedOnRepeat());
  w.pairs[1].distance = 0.3f;  // distances change with the pose; the estimate does not read them
  EXPECT_TRUE(w.iterate());
  EXPECT_TRUE(w.criteria.stoppedOnRepeat());

  // A new run (the counter back at 1) forgets the last run's pairs, unless told to carry them over.
  w.iterations = 0;
  EXPECT_FALSE(w.iterate());
  EXPECT_FALSE(w.criteria.stoppedOnRepeat());
  w.criteria.carryOverToNextRun();
  w.iterations = 0;
  EXPECT_TRUE(w.iterate());
  EXPECT_TRUE(w.criteria.stoppedOnRepeat());
}

TEST(StopRule, ADroppedOrRedirectedPairIsNotARepeat) {
  Watched w;
  EXPECT_FALSE(w.iterate());
  w.pairs.pop_back();
  EXPECT_FALSE(w.iterate());
  w.pairs[0].index_query = 2;
  EXPECT_FALSE(w.iterate());
  w.criteria.setStopOnRepeat(false);
  EXPECT_FALSE(w.iterate());  // off: PCL's tests alone
  EXPECT_FALSE(w.criteria.stoppedOnRepeat());
}

TEST(StopRule, EndsWhereTheRunWithoutItEndsInFewerIterations) {
  WEIGHTED_ICP_REQUIRE_FILE(weighted_icp::testing::realMapPath());
  const LandmarkMap map = io::readLandmarkMap(weighted_icp::testing::realMapPath()).withMinObservations(2);
  auto [target, source] = map.alternateHalves();
  source.transform(Displacement{0.1, 0.05, 0.02, 2, 1, 10}.toIsometry());
  for (const auto strategy : {WeightStrategy::Base, WeightStrategy::Covariance, WeightStrategy::Observations}) {
    for (const bool refine : {false, true}) {
      SCOPED_TRACE(toString(strategy) + (refine ? " refined" : ""));
      AlignmentSettings settings;
      settings.k = neighboursFor(strategy, 5);
      settings.refine = refine;
      settings.threads = 1;
      settings.stop_on_repeated_correspondences = false;
      const AlignmentResult without = alignLandmarkMaps(source, target, weightFunction(strategy), settings);
      settings.stop_on_repeated_correspondences = true;
      const AlignmentResult with = alignLandmarkMaps(source, target, weightFunction(strategy), settings);
      EXPECT_TRUE(with.converged);
      EXPECT_LT(with.iterations + with.refine_iterations, without.iterations + without.refine_iterations);
      EXPECT_LE(with.iterations, without.iterations);
      // The runs part where the rule stops. After that the other run repeats the same estimate, but ICP
      // re-rounds the moved source points to float each iteration, so its pose drifts by float rounding
      // of the coordinates (measured: up to 3.6e-7 in a matrix entry,
      // 1.2e-10 m^2 in fitness).
      const double moved = (with.transformation - without.transformation).cwiseAbs().maxCoeff();
      EXPECT_LT(moved, 1e-6);
      EXPECT_NEAR(with.fitness_score, without.fitness_score, 1e-6 * without.fitness_score);
    }
  }
}

}  // namespace
