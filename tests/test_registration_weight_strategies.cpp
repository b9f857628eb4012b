// The strategies' rule for k: base is plain ICP (one neighbour), the weighted ones use the k asked for.

#include <gtest/gtest.h>

#include "weighted_icp/registration/weight_strategies.h"

namespace {

using namespace weighted_icp;

TEST(WeightStrategies, BaseTakesOneNeighbourWhateverK) {
  for (const unsigned int k : {1u, 2u, 5u, 50u}) EXPECT_EQ(neighboursFor(WeightStrategy::Base, k), 1u) << "k " << k;
}

TEST(WeightStrategies, WeightedStrategiesTakeTheKAskedFor) {
  for (const WeightStrategy strategy : allWeightStrategies()) {
    if (strategy == WeightStrategy::Base) continue;
    for (const unsigned int k : {1u, 2u, 5u, 50u})
      EXPECT_EQ(neighboursFor(strategy, k), k) << toString(strategy) << ", k " << k;
  }
}

}  // namespace
