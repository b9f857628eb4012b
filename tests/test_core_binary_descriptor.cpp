// Hamming distances between binary descriptors: against a bit-by-bit count, on whichever path the CPU takes
// (popcount instruction or the portable count), and the nearest-two search against a search pair by pair.

#include <bitset>
#include <cstdint>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "weighted_icp/core/binary_descriptor.h"

namespace weighted_icp {
namespace {

int bitByBit(const BinaryDescriptor& a, const BinaryDescriptor& b) {
  int bits = 0;
  for (int w = 0; w < 4; ++w) bits += static_cast<int>(std::bitset<64>(a[w] ^ b[w]).count());
  return bits;
}

std::vector<BinaryDescriptor> randomDescriptors(std::size_t count, std::mt19937_64& random) {
  std::vector<BinaryDescriptor> result(count);
  for (auto& d : result)
    for (auto& word : d) word = random();
  return result;
}

TEST(BinaryDescriptor, HammingDistanceCountsTheDifferingBits) {
  std::mt19937_64 random(3);
  const BinaryDescriptor zero{}, ones{~0ULL, ~0ULL, ~0ULL, ~0ULL};
  EXPECT_EQ(hammingDistance(zero, zero), 0);
  EXPECT_EQ(hammingDistance(zero, ones), 256);
  EXPECT_EQ(hammingDistance(zero, BinaryDescriptor{1ULL << 63, 0, 0, 1}), 2);
  const auto a = randomDescriptors(500, random), b = randomDescriptors(500, random);
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(hammingDistance(a[i], b[i]), bitByBit(a[i], b[i])) << i;
    ASSERT_EQ(detail::portableHammingDistance(a[i], b[i]), bitByBit(a[i], b[i])) << i;
  }
}

// Rows of any length (not only 32 bytes, not aligned): the same count as bit by bit, on both paths.
TEST(BinaryDescriptor, ByteRowDistanceCountsTheDifferingBitsOfAnyLength) {
  std::mt19937_64 random(11);
  std::vector<std::uint8_t> a(80), b(80);
  for (int trial = 0; trial < 200; ++trial) {
    for (std::size_t i = 0; i < a.size(); ++i) a[i] = static_cast<std::uint8_t>(random()), b[i] = a[i];
    for (int flip = 0; flip < trial % 70; ++flip)
      b[random() % b.size()] ^= static_cast<std::uint8_t>(1u << (random() % 8));
    const int offset = trial % 3;  // unaligned starts
    for (const int bytes : {0, 1, 7, 8, 13, 16, 32, 61, 64, 77}) {
      int expected = 0;
      for (int i = 0; i < bytes; ++i)
        expected += static_cast<int>(std::bitset<8>(a[offset + i] ^ b[offset + i]).count());
      EXPECT_EQ(hammingDistance(a.data() + offset, b.data() + offset, bytes), expected) << bytes << " bytes";
      EXPECT_EQ(detail::portableHammingDistance(a.data() + offset, b.data() + offset, bytes), expected) << bytes;
    }
  }
}

TEST(BinaryDescriptor, NearestTwoIsThePairByPairSearch) {
  std::mt19937_64 random(5);
  auto candidates = randomDescriptors(300, random);
  // Equal distances: a duplicate of one candidate makes best and second equal, the first one kept.
  candidates.push_back(candidates[17]);
  for (const BinaryDescriptor& query : randomDescriptors(50, random)) {
    int best = 1000, second = 1000;
    std::size_t index = 0, second_index = 0;
    for (std::size_t i = 0; i < candidates.size(); ++i) {
      const int d = bitByBit(query, candidates[i]);
      if (d < best) {
        second = best, second_index = index, best = d, index = i;
      } else if (d < second) {
        second = d, second_index = i;
      }
    }
    for (const NearestTwo& nearest : {nearestTwo(query, candidates), detail::portableNearestTwo(query, candidates)}) {
      EXPECT_EQ(nearest.best, best);
      EXPECT_EQ(nearest.second, second);
      EXPECT_EQ(nearest.index, index);
      EXPECT_EQ(nearest.second_index, second_index);
    }
  }
  const NearestTwo to_itself = nearestTwo(candidates[17], candidates);
  EXPECT_EQ(to_itself.best, 0);
  EXPECT_EQ(to_itself.second, 0);
  EXPECT_EQ(to_itself.index, 17u);
  EXPECT_EQ(to_itself.second_index, candidates.size() - 1);  // the duplicate, after the original
}

TEST(BinaryDescriptor, NearestTwoOfTooFewCandidatesSaysSo) {
  const BinaryDescriptor query{1, 2, 3, 4};
  const NearestTwo none = nearestTwo(query, {});
  EXPECT_EQ(none.best, std::numeric_limits<int>::max());
  EXPECT_EQ(none.second, std::numeric_limits<int>::max());
  const NearestTwo one = nearestTwo(query, {BinaryDescriptor{1, 2, 3, 5}});
  EXPECT_EQ(one.best, 1);  // 4 ^ 5 = 1
  EXPECT_EQ(one.second, std::numeric_limits<int>::max());
  EXPECT_EQ(one.index, 0u);
}

}  // namespace
}  // namespace weighted_icp
