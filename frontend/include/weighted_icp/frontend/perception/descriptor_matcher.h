#pragma once
// Binary descriptor matching: FLANN's locality-sensitive hashing index
// (approximate) or brute-force Hamming search (exact; 256-bit rows by the
// popcount of core/binary_descriptor.h, others by OpenCV's BFMatcher), each
// followed by Lowe's ratio test, a distance cap and, optionally, one match per
// reference row. Issue #11: or the KD-tree paper's KD-tree with bounded backtracking.

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include "weighted_icp/core/binary_descriptor.h"
#include "weighted_icp/frontend/perception/binary_kd_tree.h"
#include "weighted_icp/frontend/perception/binary_lsh_index.h"

namespace weighted_icp::frontend {

/// FlannLsh: FLANN's LSH index. BruteForce: every row (exact). KdTree: BinaryKdTree (issue #11, the KD-tree paper),
/// exact Hamming metric, bounded backtracking. Lsh: BinaryLshIndex, FLANN's scheme and parameters in flat arrays.
enum class MatcherKind { FlannLsh, BruteForce, KdTree, Lsh };

struct DescriptorMatcherOptions {
  /// Our LSH since 2026-11-26 (FLANN's before): over five key-bit draws of each, the same accuracy (27 cross-sequence
  /// rows: mean ATE 0.497 against 0.507 cm; the 1000-frame room's open loop 0.98 against 1.05 cm) for 2.7 times less
  /// matching CPU (docs/frontend_speed.md).
  MatcherKind kind = MatcherKind::Lsh;
  float ratio = 0.8f;              // best distance < ratio * second best
  int max_hamming_distance = 64;   // bits, of 256 for ORB
  bool cross_check_unique = true;  // keep at most one query per reference: the best
  // LSH index (FLANN's and ours): hash tables, bits per hash key, neighbouring buckets
  // probed. Tuned on TUM fr1/fr3 pairs (reference 1200-1650 rows, query
  // 1000): 8/14/1 finds 97 % of the brute-force matches at under half its
  // time; 12/20/2 finds 98-99.6 % but is slower than brute force, 12/20/1 is
  // fastest but finds only 84-87 %. The key bits are drawn at random when
  // the index is built; the seed fixes them, so matches do not depend on the
  // state of OpenCV's RNG.
  int lsh_tables = 8;
  int lsh_key_bits = 14;
  int lsh_multi_probe_level = 1;
  std::uint64_t lsh_seed = 0x5eed;
  /// The KD-tree matcher's options (MatcherKind::KdTree).
  BinaryKdTreeOptions kd_tree;
};

class DescriptorMatcher {
 public:
  /// Throws std::invalid_argument for options out of range.
  explicit DescriptorMatcher(DescriptorMatcherOptions options = {});

  /// The rows to match against (CV_8U, one descriptor per row; may be empty).
  /// Builds the index once. Throws std::invalid_argument for another type.
  void setReference(const cv::Mat& descriptors);

  /// For each query row, its nearest reference row if it passes the ratio test
  /// against the second nearest (so a match needs at least two candidates)
  /// and the distance cap; sorted by queryIdx. queryIdx = query row, trainIdx
  /// = reference row, distance in bits. Empty query or reference: no matches.
  /// Throws std::invalid_argument for a query of another type or row length.
  /// Does not change the matcher: after setReference the OpenCV matcher only
  /// reads its index.
  std::vector<cv::DMatch> match(const cv::Mat& query) const;

  const DescriptorMatcherOptions& options() const { return options_; }
  int referenceSize() const { return reference_rows_; }

 private:
  /// Each query row's two nearest reference rows (fewer where the index has
  /// none), searched in parallel jobs of query rows; the same for any number of threads.
  std::vector<std::vector<cv::DMatch>> nearestTwo(const cv::Mat& query) const;
  /// nearestTwo of the brute-force matcher for 32-byte rows: every reference row, by popcount.
  std::vector<std::vector<cv::DMatch>> exhaustiveNearestTwo(const cv::Mat& query) const;

  DescriptorMatcherOptions options_;
  cv::Ptr<cv::DescriptorMatcher> matcher_;         // null until a non-empty reference is set
  BinaryKdTree::Ptr kd_tree_;                      // instead of matcher_ for MatcherKind::KdTree
  std::vector<BinaryDescriptor> reference_words_;  // instead of matcher_ for BruteForce with 32-byte rows
  BinaryLshIndex::Ptr lsh_;                        // instead of matcher_ for MatcherKind::Lsh
  int reference_rows_ = 0;
  int reference_cols_ = 0;
};

/// @brief Keeps at most one match per reference row: the one with the smallest
/// distance, then the smallest query index (the cross check every matcher applies).
/// @param matches query-to-reference matches, in query order
/// @param reference_rows rows of the reference descriptors (every trainIdx is below it)
std::vector<cv::DMatch> keepBestMatchPerReference(const std::vector<cv::DMatch>& matches, int reference_rows);

/// "flann" -> FlannLsh, "brute-force" -> BruteForce, "kd-tree" -> KdTree, "lsh" -> Lsh; throws
/// std::invalid_argument otherwise.
MatcherKind parseMatcherKind(const std::string& name);
/// The name parseMatcherKind reads.
std::string matcherKindName(MatcherKind kind);

}  // namespace weighted_icp::frontend
