#pragma once
// The one place for order statistics and error summaries: quantiles with
// numpy's default rule, the median, and RMSE/mean/median/max of a set of
// errors, as the TUM benchmark's scripts report them.

#include <vector>

namespace weighted_icp {

/// @brief Quantile of already sorted values by linear interpolation between
/// order statistics (numpy's default), so the median of an even count is the
/// mean of the middle two.
/// @param sorted values in ascending order; empty throws std::invalid_argument
/// @param p in [0, 1]; outside throws std::invalid_argument
double quantileOfSorted(const std::vector<double>& sorted, double p);

/// @brief quantileOfSorted() of the values, sorted here.
/// @param values any order; empty throws std::invalid_argument
/// @param p in [0, 1]
double quantile(std::vector<double> values, double p);

/// @brief The median (numpy.median): the mean of the two middle values for an even count.
/// @param values any order; empty throws std::invalid_argument
double median(std::vector<double> values);

/// @brief Summary of a set of non-negative errors.
struct ErrorStatistics {
  double rmse = 0.0, mean = 0.0, median = 0.0, max = 0.0;
};

/// @brief RMSE, mean, median and maximum of `errors`.
/// @param errors at least one value (else std::invalid_argument)
ErrorStatistics summarizeErrors(std::vector<double> errors);

}  // namespace weighted_icp
