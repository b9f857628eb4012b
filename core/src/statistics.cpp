// Order statistics and error summaries.
#include "weighted_icp/core/statistics.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace weighted_icp {

double quantileOfSorted(const std::vector<double>& sorted, double p) {
  if (sorted.empty()) throw std::invalid_argument("the quantile of no values is undefined");
  if (!(p >= 0.0 && p <= 1.0)) throw std::invalid_argument("a quantile must lie in [0, 1], not " + std::to_string(p));
  const double position = p * static_cast<double>(sorted.size() - 1);
  const auto below = static_cast<std::size_t>(position);
  const std::size_t above = std::min(below + 1, sorted.size() - 1);
  return sorted[below] + (position - static_cast<double>(below)) * (sorted[above] - sorted[below]);
}

double quantile(std::vector<double> values, double p) {
  std::sort(values.begin(), values.end());
  return quantileOfSorted(values, p);
}

double median(std::vector<double> values) {
  if (values.empty()) throw std::invalid_argument("the median of no values is undefined");
  // The middle one (or two) by selection: no full sort needed.
  const std::size_t middle = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(middle), values.end());
  const double upper = values[middle];
  if (values.size() % 2 == 1) return upper;
  const double lower = *std::max_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(middle));
  return 0.5 * (lower + upper);
}

ErrorStatistics summarizeErrors(std::vector<double> errors) {
  if (errors.empty()) throw std::invalid_argument("no errors to summarise");
  ErrorStatistics result;
  double sum = 0.0, sum_squares = 0.0;
  for (const double e : errors) sum += e, sum_squares += e * e;
  const double n = static_cast<double>(errors.size());
  result.rmse = std::sqrt(sum_squares / n);
  result.mean = sum / n;
  result.max = *std::max_element(errors.begin(), errors.end());
  result.median = median(std::move(errors));
  return result;
}

}  // namespace weighted_icp
