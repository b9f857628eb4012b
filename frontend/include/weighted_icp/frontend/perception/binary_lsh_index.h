#pragma once
// Locality-sensitive hashing over binary descriptors (bit sampling, multi-probe), as FLANN's LSH index does it, with
// its buckets in flat arrays and distances by popcount: the local map's matching index.

#include <cstdint>
#include <memory>
#include <vector>

#include <opencv2/core.hpp>

#include "weighted_icp/core/binary_descriptor.h"
#include "weighted_icp/frontend/perception/binary_kd_tree.h"

namespace weighted_icp::frontend {

/// @brief Build and search parameters of a BinaryLshIndex.
struct BinaryLshOptions {
  /// Hash tables, each keyed on its own bits.
  int tables = 8;
  /// Bits sampled per key (1-24): a table has 2^key_bits buckets.
  int key_bits = 14;
  /// Buckets probed per table besides the query's own: 0 none, 1 those one bit away, 2 also two bits away.
  int multi_probe_level = 1;
  /// Seed of the sampled bits: the same seed and rows give the same index, whatever else ran before.
  std::uint64_t seed = 0x5eed;
};

/// @brief The candidates of a query are the rows sharing a probed bucket with it in any table; of those, the two
/// nearest by Hamming distance are returned (so the answer is approximate: a row hashed apart in every table is
/// missed, the more likely the farther it is).
///
/// Same scheme as FLANN's LshIndex (bit-sampling keys, multi-probe by flipping key bits), the same parameters, but
/// other bits drawn, so other (equally approximate) answers. Why our own: FLANN keeps each bucket in a hash map and
/// counts bits per pair through a library call; its search was 4.0-4.7 ms of CPU for 1000 queries against 1200-1650
/// rows, a hash-table lookup 27 % of it (perf, 2026-11-26). Here a table is one offsets array over its 2^key_bits
/// buckets and one array of row indices (a counting sort), and a distance is four popcounts.
class BinaryLshIndex {
 public:
  /// @brief Shared pointer alias, PCL style.
  using Ptr = std::shared_ptr<BinaryLshIndex>;

  /// @brief Per-thread search state (which rows a query has seen); one per concurrent searcher.
  class Scratch {
    friend class BinaryLshIndex;
    std::vector<std::uint32_t> seen;  // per row: the query stamp that last saw it
    std::uint32_t stamp = 0;
  };

  /// @brief Throws std::invalid_argument for tables < 1, key_bits outside 1-24 or multi_probe_level outside 0-2.
  /// @param options the parameters an index would be built with
  static void validate(const BinaryLshOptions& options);

  /// @brief Checks the options (validate).
  /// @param options the index's parameters
  explicit BinaryLshIndex(BinaryLshOptions options = {});

  /// @brief Builds the tables on a copy of the rows.
  /// @param descriptors CV_8UC1, one descriptor per row (at least key_bits bits); may be empty.
  /// Throws std::invalid_argument for another type or rows shorter than key_bits bits.
  void build(const cv::Mat& descriptors);

  /// @brief The two nearest rows of `query` among its candidates (-1 where there are fewer); ties to the smaller row.
  /// @param query one row of as many bytes as the built rows
  /// @param scratch this thread's search state (any Scratch; sized on first use)
  TwoNearest nearestTwo(const std::uint8_t* query, Scratch& scratch) const;

  /// @brief Rows the index was built on.
  int size() const { return descriptors_.rows; }
  /// @brief "BinaryLshIndex".
  static const char* getClassName() { return "BinaryLshIndex"; }

 private:
  /// The key of `row` in `table`: its sampled bits, first sampled bit lowest.
  std::uint32_t keyOf(const std::uint8_t* row, int table) const;

  BinaryLshOptions options_;
  cv::Mat descriptors_;
  std::vector<BinaryDescriptor> words_;              // the rows again when they are 256-bit (ORB's): the fast distance
  std::vector<std::vector<int>> key_bit_positions_;  // per table, key_bits bit indices into a row
  std::vector<std::uint32_t> probe_masks_;           // XORed onto a key: 0 first, then by flipped bits
  std::vector<std::vector<std::uint32_t>> offsets_;  // per table, 2^key_bits + 1 bucket starts into rows_
  std::vector<std::vector<std::uint32_t>> rows_;     // per table, row indices by bucket
};

}  // namespace weighted_icp::frontend
