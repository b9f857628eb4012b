#pragma once
// A KD-tree over binary descriptors with bounded backtracking, as the KD-tree
// paper ("Fast scene reconstruction based on improved SLAM", Sec. 3.2) builds
// and searches it for feature matching.

#include <cstdint>
#include <memory>
#include <vector>

#include <opencv2/core.hpp>

namespace weighted_icp::frontend {

/// @brief Build and search limits of a BinaryKdTree.
struct BinaryKdTreeOptions {
  /// A node with at most this many descriptors is a leaf.
  int leaf_size = 8;
  /// Leaves visited after the first one (the paper's "backtrace time"): the
  /// search stops when it reaches this bound, or earlier when no queued branch
  /// can hold a closer descriptor (then the result is exact).
  int max_backtracks = 32;
};

/// @brief The two nearest rows of a query, by Hamming distance; -1 where none.
struct TwoNearest {
  int best = -1;
  int best_distance = 0;
  int second = -1;
  int second_distance = 0;

  /// @brief Keeps `row` if it is among the two nearest so far; ties go to the smaller row, so the result does not
  /// depend on the order rows are offered in.
  /// @param row a row index (>= 0)
  /// @param distance its Hamming distance to the query
  void offer(int row, int distance) {
    if (best < 0 || distance < best_distance || (distance == best_distance && row < best)) {
      second = best, second_distance = best_distance;
      best = row, best_distance = distance;
    } else if (second < 0 || distance < second_distance || (distance == second_distance && row < second)) {
      second = row, second_distance = distance;
    }
  }
};

/// @brief KD-tree over the bits of binary descriptors.
///
/// Reading of the paper: it describes a KD-tree whose search descends from
/// the root to the most similar branch and then backtracks, taking the queued
/// branch with the smallest distance first, while the number of backtracks is
/// below a threshold. A binary descriptor is a point of {0,1}^n, where the
/// squared Euclidean distance is the Hamming distance, so a KD-tree applies
/// as is: each node splits on one bit (the one whose ones and zeros are most
/// balanced among the node's rows, i.e. of largest variance, as a KD-tree
/// splits on the dimension of largest spread; ties to the lowest bit), and a
/// branch's distance bound is the number of split bits on its path that
/// differ from the query's (every row below differs in those bits). Build
/// and search are deterministic: no random split choice (unlike FLANN's
/// randomised trees) and a FIFO order among equal bounds.
class BinaryKdTree {
 public:
  /// @brief Shared pointer alias, PCL style.
  using Ptr = std::shared_ptr<BinaryKdTree>;

  /// @brief Checks the options. @param options leaf size >= 1, max_backtracks >= 0.
  /// Throws std::invalid_argument for options out of range.
  explicit BinaryKdTree(BinaryKdTreeOptions options = {});

  /// @brief Builds the tree on a copy of the rows.
  /// @param descriptors CV_8UC1, one descriptor per row; may be empty.
  /// Throws std::invalid_argument for another type.
  void build(const cv::Mat& descriptors);

  /// @brief The two nearest rows of `query` found within the backtracking bound.
  /// @param query one row of as many bytes as the built rows.
  TwoNearest nearestTwo(const std::uint8_t* query) const;

  /// @brief Rows the tree was built on.
  int size() const { return descriptors_.rows; }
  /// @brief Bytes per row.
  int rowBytes() const { return descriptors_.cols; }
  /// @brief "BinaryKdTree".
  static const char* getClassName() { return "BinaryKdTree"; }

 private:
  struct Node {
    int bit = -1;             // split bit; -1 for a leaf
    int child[2] = {-1, -1};  // children by the split bit's value
    int begin = 0, end = 0;   // rows order_[begin, end) for a leaf
  };
  int buildNode(int begin, int end);

  BinaryKdTreeOptions options_;
  cv::Mat descriptors_;
  std::vector<int> order_;
  std::vector<Node> nodes_;
};

}  // namespace weighted_icp::frontend
