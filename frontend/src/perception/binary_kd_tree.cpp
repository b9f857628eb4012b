// BinaryKdTree: build by balanced bit splits, search with bounded backtracking.

#include "weighted_icp/frontend/perception/binary_kd_tree.h"

#include <algorithm>
#include <queue>
#include <stdexcept>
#include <string>
#include <tuple>

#include "weighted_icp/core/binary_descriptor.h"

namespace weighted_icp::frontend {
namespace {

bool bitOf(const std::uint8_t* row, int bit) { return (row[bit >> 3] >> (bit & 7)) & 1; }

}  // namespace

BinaryKdTree::BinaryKdTree(BinaryKdTreeOptions options) : options_(options) {
  if (options_.leaf_size < 1) throw std::invalid_argument("BinaryKdTree: leaf_size must be >= 1");
  if (options_.max_backtracks < 0) throw std::invalid_argument("BinaryKdTree: max_backtracks must be >= 0");
}

void BinaryKdTree::build(const cv::Mat& descriptors) {
  if (!descriptors.empty() && descriptors.type() != CV_8UC1)
    throw std::invalid_argument("BinaryKdTree: descriptors must be CV_8UC1, got type " +
                                cv::typeToString(descriptors.type()));
  descriptors_ = descriptors.empty() ? cv::Mat() : descriptors.clone();
  nodes_.clear();
  order_.resize(static_cast<std::size_t>(descriptors_.rows));
  for (int i = 0; i < descriptors_.rows; ++i) order_[static_cast<std::size_t>(i)] = i;
  if (descriptors_.rows > 0) buildNode(0, descriptors_.rows);
}

int BinaryKdTree::buildNode(int begin, int end) {
  const int index = static_cast<int>(nodes_.size());
  nodes_.push_back({});
  nodes_[index].begin = begin;
  nodes_[index].end = end;
  const int count = end - begin;
  if (count <= options_.leaf_size) return index;
  // The most balanced bit splits: |ones - count/2| smallest.
  const int bits = descriptors_.cols * 8;
  std::vector<int> ones(static_cast<std::size_t>(bits), 0);
  for (int i = begin; i < end; ++i) {
    const std::uint8_t* row = descriptors_.ptr<std::uint8_t>(order_[static_cast<std::size_t>(i)]);
    for (int b = 0; b < bits; ++b) ones[static_cast<std::size_t>(b)] += bitOf(row, b);
  }
  int best_bit = -1, best_imbalance = count;
  for (int b = 0; b < bits; ++b) {
    const int imbalance = std::abs(2 * ones[static_cast<std::size_t>(b)] - count);
    if (imbalance < best_imbalance) {
      best_imbalance = imbalance;
      best_bit = b;
    }
  }
  if (best_bit < 0 || best_imbalance == count) return index;  // all rows equal: a leaf
  // Zeros first, keeping the rows' order within each side (deterministic).
  const auto middle = std::stable_partition(order_.begin() + begin, order_.begin() + end, [&](int row) {
    return !bitOf(descriptors_.ptr<std::uint8_t>(row), best_bit);
  });
  const int split = static_cast<int>(middle - order_.begin());
  const int zero_child = buildNode(begin, split);
  const int one_child = buildNode(split, end);
  nodes_[index].bit = best_bit;
  nodes_[index].child[0] = zero_child;
  nodes_[index].child[1] = one_child;
  return index;
}

TwoNearest BinaryKdTree::nearestTwo(const std::uint8_t* query) const {
  TwoNearest result;
  if (nodes_.empty()) return result;
  const int infinite = descriptors_.cols * 8 + 1;
  result.best_distance = result.second_distance = infinite;
  // (bound, sequence, node): smallest bound first, then first queued.
  using Entry = std::tuple<int, long, int>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue;
  long sequence = 0;
  queue.emplace(0, sequence++, 0);
  int leaves = 0;
  while (!queue.empty()) {
    auto [bound, order, node] = queue.top();
    (void)order;
    queue.pop();
    // No row below can beat the second nearest: what is found is exact.
    if (bound >= result.second_distance) break;
    if (leaves > options_.max_backtracks) break;  // the first leaf is not a backtrack
    // Descend towards the query's side, queueing the other side one bit further.
    while (nodes_[static_cast<std::size_t>(node)].bit >= 0) {
      const Node& n = nodes_[static_cast<std::size_t>(node)];
      const int side = bitOf(query, n.bit);
      queue.emplace(bound + 1, sequence++, n.child[1 - side]);
      node = n.child[side];
    }
    ++leaves;
    const Node& leaf = nodes_[static_cast<std::size_t>(node)];
    for (int i = leaf.begin; i < leaf.end; ++i) {
      const int row = order_[static_cast<std::size_t>(i)];
      const int d = hammingDistance(query, descriptors_.ptr<std::uint8_t>(row), descriptors_.cols);
      result.offer(row, d);
    }
  }
  if (result.best < 0) result.best_distance = 0;
  if (result.second < 0) result.second_distance = 0;
  return result;
}

}  // namespace weighted_icp::frontend
