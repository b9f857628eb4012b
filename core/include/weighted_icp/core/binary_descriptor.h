#pragma once
// A 256-bit binary (ORB) descriptor as four 64-bit words, and Hamming distances between them: one pair, or the
// nearest two of many (the exhaustive searches of the front end's descriptor matcher and of loop verification).
// The popcount instruction is used where the CPU has it (checked once at run time; the binaries are built for the
// x86-64 baseline, which lacks it). In core because the front end and the mapping layer both match descriptors.

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include <opencv2/core.hpp>

namespace weighted_icp {

/// @brief One 256-bit binary descriptor (an ORB row of 32 bytes) as four words, so that Hamming
/// distances are four popcounts.
using BinaryDescriptor = std::array<std::uint64_t, 4>;

/// @brief Hamming distance between two descriptors (0..256).
/// @param a first descriptor
/// @param b second descriptor
int hammingDistance(const BinaryDescriptor& a, const BinaryDescriptor& b);

/// @brief Hamming distance between two binary descriptors of any length, given as bytes (an OpenCV descriptor
/// row): what cv::hal::normHamming computes, by the popcount instruction where the CPU has it.
/// @param a first descriptor's bytes
/// @param b second descriptor's bytes
/// @param bytes length of each (>= 0)
int hammingDistance(const std::uint8_t* a, const std::uint8_t* b, int bytes);

/// @brief The two smallest Hamming distances from a query to a set of descriptors.
struct NearestTwo {
  /// The smallest distance; max() when the set is empty.
  int best = std::numeric_limits<int>::max();
  /// The second smallest (equal to best when two share it); max() with fewer than two descriptors.
  int second = std::numeric_limits<int>::max();
  /// Where best is (the first of equals); 0 when the set is empty.
  std::size_t index = 0;
  /// Where second is (the first of equals after index); 0 with fewer than two descriptors.
  std::size_t second_index = 0;
};

/// @brief The nearest and second-nearest of `candidates` to `query` by Hamming distance, by exhaustive search
/// (the same result as comparing with hammingDistance one by one).
/// @param query the descriptor searched for
/// @param candidates the descriptors searched
NearestTwo nearestTwo(const BinaryDescriptor& query, const std::vector<BinaryDescriptor>& candidates);

namespace detail {
/// @brief hammingDistance without the popcount instruction (what a CPU without it runs; for tests).
int portableHammingDistance(const BinaryDescriptor& a, const BinaryDescriptor& b);
/// @brief hammingDistance of byte rows without the popcount instruction (for tests).
int portableHammingDistance(const std::uint8_t* a, const std::uint8_t* b, int bytes);
/// @brief nearestTwo without the popcount instruction (what a CPU without it runs; for tests).
NearestTwo portableNearestTwo(const BinaryDescriptor& query, const std::vector<BinaryDescriptor>& candidates);
}  // namespace detail

/// @brief The rows of an ORB descriptor matrix as BinaryDescriptors.
/// @param descriptors CV_8U with 32 columns (or empty); anything else throws std::invalid_argument
std::vector<BinaryDescriptor> toBinaryDescriptors(const cv::Mat& descriptors);

}  // namespace weighted_icp
