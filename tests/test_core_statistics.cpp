// The one statistics helper: numpy's quantile rule, the median, error summaries.
#include <cmath>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "weighted_icp/core/statistics.h"

using namespace weighted_icp;

TEST(Statistics, QuantilesInterpolateBetweenOrderStatisticsAsNumpy) {
  // numpy.quantile([1, 2, 4, 8], [0, 0.25, 0.5, 0.9, 1]) = 1, 1.75, 3, 6.8, 8
  const std::vector<double> values{8.0, 1.0, 4.0, 2.0};
  EXPECT_DOUBLE_EQ(quantile(values, 0.0), 1.0);
  EXPECT_DOUBLE_EQ(quantile(values, 0.25), 1.75);
  EXPECT_DOUBLE_EQ(quantile(values, 0.5), 3.0);
  EXPECT_DOUBLE_EQ(quantile(values, 0.9), 6.8);
  EXPECT_DOUBLE_EQ(quantile(values, 1.0), 8.0);
  EXPECT_DOUBLE_EQ(quantileOfSorted({5.0}, 0.7), 5.0);
}

TEST(Statistics, MedianOfAnEvenCountIsTheMeanOfTheMiddleTwo) {
  EXPECT_DOUBLE_EQ(median({3.0, 1.0, 2.0}), 2.0);
  EXPECT_DOUBLE_EQ(median({4.0, 1.0, 3.0, 2.0}), 2.5);
  EXPECT_DOUBLE_EQ(median({7.0}), 7.0);
  // The median agrees with the 0.5 quantile whatever the order.
  const std::vector<double> values{0.3, 9.1, -2.0, 4.4, 4.4, 1.0, 8.5, -0.1};
  EXPECT_DOUBLE_EQ(median(values), quantile(values, 0.5));
}

TEST(Statistics, EmptyInputsAndBadQuantilesAreRefused) {
  EXPECT_THROW(median({}), std::invalid_argument);
  EXPECT_THROW(quantile({}, 0.5), std::invalid_argument);
  EXPECT_THROW(quantile({1.0}, 1.5), std::invalid_argument);
  EXPECT_THROW(quantile({1.0}, std::nan("")), std::invalid_argument);
  EXPECT_THROW(summarizeErrors({}), std::invalid_argument);
}

TEST(Statistics, ErrorSummaryHasRmseMeanMedianAndMax) {
  const ErrorStatistics s = summarizeErrors({3.0, 4.0, 0.0, 1.0});
  EXPECT_DOUBLE_EQ(s.rmse, std::sqrt((9.0 + 16.0 + 0.0 + 1.0) / 4.0));
  EXPECT_DOUBLE_EQ(s.mean, 2.0);
  EXPECT_DOUBLE_EQ(s.median, 2.0);
  EXPECT_DOUBLE_EQ(s.max, 4.0);
}
