// BinaryLshIndex: bit-sampling keys, buckets as a counting sort per table, multi-probe search by popcount.

#include "weighted_icp/frontend/perception/binary_lsh_index.h"

#include <algorithm>
#include <cstring>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>

#include "weighted_icp/core/binary_descriptor.h"

namespace weighted_icp::frontend {

namespace {

void requireOption(bool valid, const std::string& what) {
  if (!valid) throw std::invalid_argument(std::string("BinaryLshIndex: ") + what);
}

/// Keys XORed onto the query's own: itself, then every key `level` or fewer bits away, by fewer flips first.
std::vector<std::uint32_t> probeMasks(int key_bits, int level) {
  std::vector<std::uint32_t> masks{0u};
  if (level >= 1)
    for (int a = 0; a < key_bits; ++a) masks.push_back(1u << a);
  if (level >= 2)
    for (int a = 0; a < key_bits; ++a)
      for (int b = a + 1; b < key_bits; ++b) masks.push_back((1u << a) | (1u << b));
  return masks;
}

}  // namespace

void BinaryLshIndex::validate(const BinaryLshOptions& options) {
  requireOption(options.tables >= 1, "tables must be >= 1");
  requireOption(options.key_bits >= 1 && options.key_bits <= 24, "key_bits must be in [1, 24]");
  requireOption(options.multi_probe_level >= 0 && options.multi_probe_level <= 2,
                "multi_probe_level must be 0, 1 or 2");
}

BinaryLshIndex::BinaryLshIndex(BinaryLshOptions options) : options_(options) {
  validate(options_);
  probe_masks_ = probeMasks(options_.key_bits, options_.multi_probe_level);
}

std::uint32_t BinaryLshIndex::keyOf(const std::uint8_t* row, int table) const {
  std::uint32_t key = 0;
  const std::vector<int>& bits = key_bit_positions_[static_cast<std::size_t>(table)];
  for (std::size_t i = 0; i < bits.size(); ++i)
    key |= static_cast<std::uint32_t>((row[bits[i] >> 3] >> (bits[i] & 7)) & 1u) << i;
  return key;
}

void BinaryLshIndex::build(const cv::Mat& descriptors) {
  if (!descriptors.empty() && descriptors.type() != CV_8UC1)
    throw std::invalid_argument("BinaryLshIndex: descriptors must be CV_8UC1 (binary), got type " +
                                cv::typeToString(descriptors.type()));
  if (!descriptors.empty() && descriptors.cols * 8 < options_.key_bits)
    throw std::invalid_argument("BinaryLshIndex: rows of " + std::to_string(descriptors.cols * 8) +
                                " bits are shorter than a key of " + std::to_string(options_.key_bits));
  descriptors_ = descriptors.empty() ? cv::Mat() : descriptors.clone();
  key_bit_positions_.clear(), offsets_.clear(), rows_.clear(), words_.clear();
  if (descriptors_.empty()) return;
  if (descriptors_.cols == static_cast<int>(sizeof(BinaryDescriptor))) words_ = toBinaryDescriptors(descriptors_);

  // Each table samples key_bits distinct bits of the row; the draws depend on the seed only.
  std::mt19937_64 random(options_.seed);
  std::vector<int> all_bits(static_cast<std::size_t>(descriptors_.cols * 8));
  std::iota(all_bits.begin(), all_bits.end(), 0);
  const std::size_t buckets = std::size_t{1} << options_.key_bits;
  const int rows = descriptors_.rows;
  for (int t = 0; t < options_.tables; ++t) {
    for (std::size_t i = 0; i < static_cast<std::size_t>(options_.key_bits); ++i)  // partial Fisher-Yates
      std::swap(all_bits[i], all_bits[i + random() % (all_bits.size() - i)]);
    key_bit_positions_.emplace_back(all_bits.begin(), all_bits.begin() + options_.key_bits);
    // Counting sort of the rows by key: offsets[k] .. offsets[k + 1] are bucket k's rows, in row order.
    std::vector<std::uint32_t> keys(static_cast<std::size_t>(rows));
    std::vector<std::uint32_t> offsets(buckets + 1, 0);
    for (int r = 0; r < rows; ++r) ++offsets[(keys[static_cast<std::size_t>(r)] = keyOf(descriptors_.ptr(r), t)) + 1];
    std::partial_sum(offsets.begin(), offsets.end(), offsets.begin());
    std::vector<std::uint32_t> sorted(static_cast<std::size_t>(rows));
    std::vector<std::uint32_t> next(offsets.begin(), offsets.end() - 1);
    for (int r = 0; r < rows; ++r) sorted[next[keys[static_cast<std::size_t>(r)]]++] = static_cast<std::uint32_t>(r);
    offsets_.push_back(std::move(offsets));
    rows_.push_back(std::move(sorted));
  }
}

TwoNearest BinaryLshIndex::nearestTwo(const std::uint8_t* query, Scratch& scratch) const {
  TwoNearest result;
  if (descriptors_.empty()) return result;
  const std::size_t rows = static_cast<std::size_t>(descriptors_.rows);
  if (scratch.seen.size() != rows || scratch.stamp == UINT32_MAX) scratch.seen.assign(rows, 0), scratch.stamp = 0;
  const std::uint32_t stamp = ++scratch.stamp;
  const int bytes = descriptors_.cols;
  BinaryDescriptor query_words{};  // 256-bit rows: four popcounts per distance, no per-word copies
  if (!words_.empty()) std::memcpy(query_words.data(), query, sizeof(BinaryDescriptor));
  for (int t = 0; t < options_.tables; ++t) {
    const std::uint32_t key = keyOf(query, t);
    const std::vector<std::uint32_t>& offsets = offsets_[static_cast<std::size_t>(t)];
    const std::vector<std::uint32_t>& table_rows = rows_[static_cast<std::size_t>(t)];
    for (const std::uint32_t mask : probe_masks_) {
      const std::uint32_t bucket = key ^ mask;
      for (std::uint32_t i = offsets[bucket]; i < offsets[bucket + 1]; ++i) {
        const std::uint32_t row = table_rows[i];
        if (scratch.seen[row] == stamp) continue;  // a candidate of an earlier table or probe
        scratch.seen[row] = stamp;
        const int d = words_.empty() ? hammingDistance(query, descriptors_.ptr(static_cast<int>(row)), bytes)
                                     : hammingDistance(query_words, words_[row]);
        result.offer(static_cast<int>(row), d);
      }
    }
  }
  if (result.best < 0) result.best_distance = 0;
  if (result.second < 0) result.second_distance = 0;
  return result;
}

}  // namespace weighted_icp::frontend
