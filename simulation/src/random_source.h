#pragma once
// The simulators' one deterministic random source: an mt19937_64 engine and a
// counter-based hash (splitmix64), mapped to numbers by our own transforms and
// one Box-Muller, so that outputs do not depend on the standard library's
// distributions (implementation-defined) and are the same on every toolchain
// for a seed. Private to the simulation library.

#include <algorithm>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

#include <Eigen/Core>

namespace weighted_icp::simulation {

/// @brief splitmix64's finaliser: a well-mixed 64-bit hash, for sub-seeds and
/// per-pixel noise (inline: the renderer calls it for every pixel).
inline std::uint64_t mixBits(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

/// @brief [0, 1) from the top 53 bits of `bits`.
inline double unitInterval(std::uint64_t bits) { return static_cast<double>(bits >> 11) * 0x1.0p-53; }

/// @brief Stream `stream`, item `index` of `seed`: independent sub-seeds of
/// one seed, so that options do not shift each other's draws.
std::uint64_t subSeed(std::uint64_t seed, std::uint64_t stream, std::uint64_t index = 0);

/// @brief Box-Muller: two independent standard normal deviates.
/// @param radius_uniform uniform in (0, 1] (0 would give an infinite radius)
/// @param angle_uniform uniform in [0, 1)
std::pair<double, double> boxMuller(double radius_uniform, double angle_uniform);

/// @brief 65536 standard normal deviates (Box-Muller on the hashes of 0, 1, 2, ...),
/// to be picked by a hash: cheaper per pixel than a log and a sincos.
const std::vector<float>& hashedNormalTable();

/// @brief Uniform, integer and normal draws from one std::mt19937_64.
class RandomSource {
 public:
  /// @brief The engine seeded with `seed` itself (the RGB-D sequence derives
  /// its streams with subSeed()).
  explicit RandomSource(std::uint64_t seed) : engine_(seed) {}
  /// @brief Stream `stream` of `seed` through std::seed_seq (the session's
  /// streams: changing, say, the drift leaves a seed's landmark layout as it was).
  RandomSource(std::uint64_t seed, std::uint32_t stream) {
    std::seed_seq sequence{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32), stream};
    engine_.seed(sequence);
  }

  /// @brief [0, 1): 53 random bits.
  double unit() { return unitInterval(engine_()); }
  /// @brief The open interval (0, 1): 53 random bits, centred in their cell.
  double openUnit() { return (static_cast<double>(engine_() >> 11) + 0.5) * 0x1.0p-53; }
  /// @brief [low, high), from unit().
  double uniform(double low, double high) { return low + (high - low) * unit(); }
  /// @brief (low, high), from openUnit().
  double openUniform(double low, double high) { return low + (high - low) * openUnit(); }
  /// @brief An integer in [low, high_inclusive].
  int integer(int low, int high_inclusive) {
    return std::min(high_inclusive, low + static_cast<int>(uniform(0.0, high_inclusive - low + 1.0)));
  }
  /// @brief True with the given probability.
  bool chance(double probability) { return uniform(0.0, 1.0) < probability; }
  /// @brief A standard normal deviate: the first of Box-Muller's pair on two openUnit() draws.
  double normal();
  /// @brief Three standard normal deviates, drawn x, y, z in that order.
  Eigen::Vector3d normal3() {
    const double x = normal(), y = normal(), z = normal();
    return {x, y, z};
  }

 private:
  std::mt19937_64 engine_;
};

}  // namespace weighted_icp::simulation
