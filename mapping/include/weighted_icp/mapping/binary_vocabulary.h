#pragma once
// A vocabulary tree over binary (ORB) descriptors, as DBoW2 builds it:
// hierarchical k-majority clustering in Hamming space, TF-IDF word weights,
// and bag-of-words vectors compared with the L1 score.

#include <array>
#include <cstddef>
#include <cstdint>
#include <iosfwd>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "weighted_icp/core/binary_descriptor.h"

namespace weighted_icp::mapping {

/// @brief A word id: the index of a leaf of the tree (0 .. wordCount() - 1).
using WordId = std::uint32_t;

/// @brief A bag-of-words vector: TF-IDF weight per word, L1-normalised (weights sum to 1).
using BowVector = std::map<WordId, double>;

/// @brief How to grow the tree.
struct VocabularyTrainingOptions {
  /// Children per node (k of k-majority); DBoW2's ORB vocabulary uses 10.
  unsigned int branching = 10;
  /// Levels below the root; up to branching^depth words.
  unsigned int depth = 4;
  /// k-majority rounds per node at most (they stop earlier when no assignment changes).
  unsigned int max_iterations = 10;
  /// Seeds k-means++ (the first centre and each later draw); training is deterministic for it.
  std::uint64_t seed = 1;
};

/// @brief The vocabulary tree. Immutable once trained or loaded, so one instance can be shared
/// by threads (transform and score are const and keep no state).
class BinaryVocabulary {
 public:
  using Ptr = std::shared_ptr<BinaryVocabulary>;
  using ConstPtr = std::shared_ptr<const BinaryVocabulary>;

  /// @brief Trains the tree on the descriptors of a set of training images.
  ///
  /// Each node's descriptors are split into `branching` clusters by k-majority (k-means in Hamming
  /// space: a centre's bit is the majority bit of its members), seeded by k-means++; recursion stops at
  /// `depth` or when a node has no more descriptors than children. A word's weight is its inverse
  /// document frequency log(N / n_i) over the N images (n_i images contain the word; a word no image
  /// contains gets log N).
  /// @param images one descriptor matrix per training image (CV_8U, 32 columns; empty ones count as images)
  /// @param options branching >= 2, depth >= 1, max_iterations >= 1; else std::invalid_argument
  /// @return the vocabulary; std::invalid_argument when there are no descriptors at all
  static BinaryVocabulary train(const std::vector<cv::Mat>& images, const VocabularyTrainingOptions& options = {});

  /// @brief Reads the text format that save() writes (docs/place_recognition.md).
  /// @param path the file; std::runtime_error names it, and the line, for anything wrong in it
  static BinaryVocabulary load(const std::string& path);
  /// @brief Reads the text format from a stream.
  /// @param in the stream
  /// @param name what errors call the source (a file name)
  static BinaryVocabulary read(std::istream& in, const std::string& name);
  /// @brief Writes the text format (the tool writes it atomically, through io::writeAtomically).
  /// @param out the stream; std::runtime_error when it fails
  void write(std::ostream& out) const;

  /// @brief The class name, as PCL classes report it.
  static std::string getClassName() { return "BinaryVocabulary"; }

  /// @brief Number of words (leaves).
  std::size_t wordCount() const { return words_.size(); }
  /// @brief Children per node it was trained with.
  unsigned int branching() const { return branching_; }
  /// @brief Levels below the root it was trained with.
  unsigned int depth() const { return depth_; }
  /// @brief The IDF weight of a word.
  /// @param word 0 <= word < wordCount(), else std::out_of_range
  double weight(WordId word) const;

  /// @brief The word of one descriptor: descends the tree, taking the nearest child at each level.
  /// @param descriptor the descriptor
  WordId wordOf(const BinaryDescriptor& descriptor) const;
  /// @brief The bag-of-words vector of an image: term frequency times IDF per word, L1-normalised.
  /// @param descriptors CV_8U, 32 columns (empty gives an empty vector); else std::invalid_argument
  BowVector transform(const cv::Mat& descriptors) const;

  /// @brief DBoW2's L1 score of two L1-normalised vectors: 1 - |a - b|_1 / 2, in [0, 1]
  /// (1: the same words in the same proportions, 0: no word in common).
  /// @param a first vector
  /// @param b second vector
  static double score(const BowVector& a, const BowVector& b);

 private:
  struct Node {
    BinaryDescriptor centre{};
    std::vector<std::uint32_t> children;  // node indices; empty for a leaf
    WordId word = 0;                      // leaves only
  };
  class Trainer;
  BinaryVocabulary() = default;

  unsigned int branching_ = 0, depth_ = 0;
  std::vector<Node> nodes_;           // nodes_[0] is the root (no centre)
  std::vector<std::uint32_t> words_;  // word id -> node index
  std::vector<double> weights_;       // word id -> IDF
};

}  // namespace weighted_icp::mapping
