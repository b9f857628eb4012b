// The simulators' random source: sub-seeds, Box-Muller and the hashed normal
// table (see random_source.h).

#include "random_source.h"

#include <cmath>

namespace weighted_icp::simulation {

namespace {
constexpr double kPi = 3.14159265358979323846;
}  // namespace

std::uint64_t subSeed(std::uint64_t seed, std::uint64_t stream, std::uint64_t index) {
  return mixBits(mixBits(seed ^ (stream << 56)) + index);
}

std::pair<double, double> boxMuller(double radius_uniform, double angle_uniform) {
  const double radius = std::sqrt(-2.0 * std::log(radius_uniform));
  const double angle = 2.0 * kPi * angle_uniform;
  return {radius * std::cos(angle), radius * std::sin(angle)};
}

const std::vector<float>& hashedNormalTable() {
  static const std::vector<float> table = [] {
    std::vector<float> values(1 << 16);
    for (std::size_t k = 0; k < values.size(); k += 2) {
      // 1 - u is in (0, 1], as Box-Muller's radius needs.
      const auto [first, second] = boxMuller(1.0 - unitInterval(mixBits(2 * k)), unitInterval(mixBits(2 * k + 1)));
      values[k] = static_cast<float>(first);
      values[k + 1] = static_cast<float>(second);
    }
    return values;
  }();
  return table;
}

double RandomSource::normal() {
  // Sequenced: the radius's draw comes first, as the sessions of every seed were made.
  const double radius_uniform = openUnit();
  const double angle_uniform = openUnit();
  return boxMuller(radius_uniform, angle_uniform).first;
}

}  // namespace weighted_icp::simulation
