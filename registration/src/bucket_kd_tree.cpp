// BucketKdTree: median splits on the widest axis, leaves as contiguous xyz runs, exact pruning in float.
#include "weighted_icp/registration/bucket_kd_tree.h"

#include <algorithm>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <utility>

#include "weighted_icp/registration/nearest_neighbor_index.h"

namespace weighted_icp {

/// The `capacity` smallest distances seen, sorted; a distance equal to the current worst does not enter.
/// Each entry is one 64-bit key, the distance's bits above the row: squared distances are never negative,
/// so their bit patterns sort as the floats do, and shifting an entry is one move instead of two.
struct BucketKdTree::Nearest {
  static constexpr std::size_t kMaxCapacity = 64;
  explicit Nearest(std::size_t capacity) : capacity(capacity) {}
  bool admits(float gap) const { return gap < worst; }
  bool add(float d, Row row) {
    if (!(d < worst)) return true;
    std::uint32_t bits;
    std::memcpy(&bits, &d, sizeof bits);
    const std::uint64_t key = (static_cast<std::uint64_t>(bits) << 32) | row;
    std::size_t i = found < capacity ? found++ : capacity - 1;
    for (; i > 0 && keys[i - 1] > key; --i) keys[i] = keys[i - 1];
    keys[i] = key;
    if (found == capacity) worst = distanceOf(keys[capacity - 1]);
    return true;
  }
  static float distanceOf(std::uint64_t key) {
    const auto bits = static_cast<std::uint32_t>(key >> 32);
    float d;
    std::memcpy(&d, &bits, sizeof d);
    return d;
  }
  std::size_t capacity;
  std::size_t found = 0;
  float worst = std::numeric_limits<float>::infinity();
  std::uint64_t keys[kMaxCapacity];
};

/// The same for any capacity, in the caller's arrays (two moves per shifted entry).
struct BucketKdTree::NearestMany {
  bool admits(float gap) const { return gap < worst; }
  bool add(float d, Row row) {
    if (!(d < worst)) return true;
    std::size_t i = found < capacity ? found++ : capacity - 1;
    for (; i > 0 && distances[i - 1] > d; --i) {
      distances[i] = distances[i - 1];
      rows[i] = rows[i - 1];
    }
    distances[i] = d;
    rows[i] = row;
    if (found == capacity) worst = distances[capacity - 1];
    return true;
  }
  std::size_t capacity;
  Row* rows;
  float* distances;
  std::size_t found = 0;
  float worst = std::numeric_limits<float>::infinity();
};

/// Every row within a squared radius, up to a limit.
struct BucketKdTree::Within {
  bool admits(float gap) const { return gap <= radius_sq; }
  bool add(float d, Row row) {
    if (d <= radius_sq) rows.push_back(row);
    return rows.size() <= limit;
  }
  float radius_sq;
  std::size_t limit;
  std::vector<Row>& rows;
};

void BucketKdTree::build(const float* xyz, std::size_t n, std::size_t leaf_size) {
  if (n > std::numeric_limits<Row>::max()) throw std::invalid_argument("more than 4,294,967,295 points to index");
  nodes_.clear();
  xs_.clear();
  ys_.clear();
  zs_.clear();
  rows_.clear();
  if (n == 0) return;
  leaf_size = std::clamp<std::size_t>(leaf_size, 1, kMaxLeafSize);
  std::vector<Row> order(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = static_cast<Row>(i);
  nodes_.reserve(2 * (n / leaf_size) + 1);
  nodes_.push_back(Node{});
  nodes_[0].end = static_cast<std::uint32_t>(n);
  split(0, order, xyz, leaf_size);
  xs_.resize(n);
  ys_.resize(n);
  zs_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    xs_[i] = xyz[3 * order[i]];
    ys_[i] = xyz[3 * order[i] + 1];
    zs_[i] = xyz[3 * order[i] + 2];
  }
  rows_ = std::move(order);
}

void BucketKdTree::split(std::uint32_t node, std::vector<Row>& order, const float* xyz, std::size_t leaf_size) {
  const std::uint32_t begin = nodes_[node].begin;
  const std::uint32_t end = nodes_[node].end;
  if (end - begin <= leaf_size) return;
  // The widest axis of the node's points.
  float lo[3], hi[3];
  for (int a = 0; a < 3; ++a) lo[a] = hi[a] = xyz[3 * order[begin] + a];
  for (std::uint32_t i = begin + 1; i < end; ++i)
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], xyz[3 * order[i] + a]);
      hi[a] = std::max(hi[a], xyz[3 * order[i] + a]);
    }
  std::uint32_t axis = 0;
  for (std::uint32_t a = 1; a < 3; ++a)
    if (hi[a] - lo[a] > hi[axis] - lo[axis]) axis = a;
  // The median by count: both halves shrink even when every point is the same one.
  const std::uint32_t mid = begin + (end - begin) / 2;
  const auto coordinate = [&](Row row) { return xyz[3 * row + axis]; };
  std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end,
                   [&](Row a, Row b) { return coordinate(a) < coordinate(b); });
  float low = coordinate(order[begin]);
  for (std::uint32_t i = begin + 1; i < mid; ++i) low = std::max(low, coordinate(order[i]));
  float high = coordinate(order[mid]);
  for (std::uint32_t i = mid + 1; i < end; ++i) high = std::min(high, coordinate(order[i]));
  const auto first = static_cast<std::uint32_t>(nodes_.size());
  Node left, right;
  left.begin = begin;
  left.end = right.begin = mid;
  right.end = end;
  nodes_.push_back(left);
  nodes_.push_back(right);
  Node& self = nodes_[node];
  self.low = low;
  self.high = high;
  self.axis = axis;
  self.first = first;
  split(first, order, xyz, leaf_size);
  split(first + 1, order, xyz, leaf_size);
}

template <typename Result>
bool BucketKdTree::descend(std::uint32_t index, const float* query, float* gaps, Result& result) const {
  const Node& node = nodes_[index];
  if (node.first == 0) {
    // Distances of the whole leaf first, in squaredDistance()'s order of operations: a loop the compiler
    // vectorizes over the leaf's contiguous coordinates, with the same float results as one at a time.
    const std::uint32_t count = node.end - node.begin;
    const float* x = xs_.data() + node.begin;
    const float* y = ys_.data() + node.begin;
    const float* z = zs_.data() + node.begin;
    float distances[kMaxLeafSize];
    for (std::uint32_t i = 0; i < count; ++i) {
      const float d0 = query[0] - x[i];
      const float d1 = query[1] - y[i];
      const float d2 = query[2] - z[i];
      float d = d0 * d0;
      d += d1 * d1;
      d += d2 * d2;
      distances[i] = d;
    }
    const Row* rows = rows_.data() + node.begin;
    for (std::uint32_t i = 0; i < count; ++i)
      if (!result.add(distances[i], rows[i])) return false;
    return true;
  }
  const std::uint32_t axis = node.axis;
  const float to_low = query[axis] - node.low;
  const float to_high = query[axis] - node.high;
  // The nearer child first; the other lies beyond its plane by `cut` on this axis.
  std::uint32_t near_child, far_child;
  float cut;
  if (to_low + to_high < 0.0f) {
    near_child = node.first;
    far_child = node.first + 1;
    cut = to_high < 0.0f ? to_high * to_high : 0.0f;
  } else {
    near_child = node.first + 1;
    far_child = node.first;
    cut = to_low > 0.0f ? to_low * to_low : 0.0f;
  }
  if (!descend(near_child, query, gaps, result)) return false;
  const float saved = gaps[axis];
  gaps[axis] = cut;
  // Summed in squaredDistance()'s order, so the bound is at most any far point's float distance.
  float bound = gaps[0] + gaps[1];
  bound += gaps[2];
  const bool go_on = !result.admits(bound) || descend(far_child, query, gaps, result);
  gaps[axis] = saved;
  return go_on;
}

std::size_t BucketKdTree::nearest(const float* query, std::size_t count, Row* rows, float* distances) const {
  count = std::min(count, size());
  if (count == 0) return 0;
  float gaps[3] = {0.0f, 0.0f, 0.0f};
  if (count > Nearest::kMaxCapacity) {
    NearestMany result{count, rows, distances};
    descend(0, query, gaps, result);
    return result.found;
  }
  Nearest result(count);
  descend(0, query, gaps, result);
  for (std::size_t i = 0; i < result.found; ++i) {
    rows[i] = static_cast<Row>(result.keys[i]);
    distances[i] = Nearest::distanceOf(result.keys[i]);
  }
  return result.found;
}

bool BucketKdTree::within(const float* query, float radius_sq, std::size_t limit, std::vector<Row>& rows) const {
  if (size() == 0) return true;
  Within result{radius_sq, limit, rows};
  float gaps[3] = {0.0f, 0.0f, 0.0f};
  return descend(0, query, gaps, result);
}

}  // namespace weighted_icp
