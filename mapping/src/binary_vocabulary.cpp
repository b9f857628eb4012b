// The vocabulary tree (see binary_vocabulary.h): k-majority training, the
// descent that turns a descriptor into a word, TF-IDF vectors, the L1 score
// and the text format.

#include "weighted_icp/mapping/binary_vocabulary.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <istream>
#include <limits>
#include <ostream>
#include <random>
#include <sstream>
#include <stdexcept>

#include "text_records.h"

namespace weighted_icp::mapping {

namespace {

constexpr int kDescriptorBytes = static_cast<int>(sizeof(BinaryDescriptor));
constexpr const char* kMagic = "wicp_vocabulary";
constexpr int kFormatVersion = 1;

}  // namespace

// --- Training: one node at a time, depth first, so node indices are parents first.

class BinaryVocabulary::Trainer {
 public:
  Trainer(const std::vector<BinaryDescriptor>& descriptors, const VocabularyTrainingOptions& options,
          BinaryVocabulary& vocabulary)
      : descriptors_(descriptors), options_(options), vocabulary_(vocabulary), random_(options.seed) {}

  void grow(std::uint32_t node, const std::vector<std::uint32_t>& members, unsigned int level) {
    if (level >= options_.depth || members.size() <= options_.branching) return;
    std::vector<BinaryDescriptor> centres = seedCentres(members);
    std::vector<std::uint32_t> assignment(members.size(), 0);
    for (unsigned int iteration = 0; iteration < options_.max_iterations; ++iteration) {
      const bool changed = assign(members, centres, assignment) || iteration == 0;
      if (!changed) break;
      centres = majorityCentres(members, assignment, centres);
    }
    assign(members, centres, assignment);
    std::vector<std::vector<std::uint32_t>> clusters(centres.size());
    for (std::size_t i = 0; i < members.size(); ++i) clusters[assignment[i]].push_back(members[i]);
    for (std::size_t c = 0; c < centres.size(); ++c) {
      if (clusters[c].empty()) continue;  // a centre that lost every member is dropped
      const auto child = static_cast<std::uint32_t>(vocabulary_.nodes_.size());
      vocabulary_.nodes_.push_back({centres[c], {}, 0});
      vocabulary_.nodes_[node].children.push_back(child);
      grow(child, clusters[c], level + 1);
    }
  }

 private:
  /// k-means++: the first centre at random, each next one drawn with probability proportional to the
  /// squared distance to the nearest centre so far. Duplicates are never drawn twice (distance 0).
  std::vector<BinaryDescriptor> seedCentres(const std::vector<std::uint32_t>& members) {
    std::vector<BinaryDescriptor> centres;
    centres.push_back(descriptors_[members[random_() % members.size()]]);
    std::vector<double> nearest(members.size(), std::numeric_limits<double>::max());
    while (centres.size() < options_.branching) {
      double total = 0.0;
      for (std::size_t i = 0; i < members.size(); ++i) {
        const double d = hammingDistance(descriptors_[members[i]], centres.back());
        nearest[i] = std::min(nearest[i], d * d);
        total += nearest[i];
      }
      if (total <= 0.0) break;  // fewer distinct descriptors than children
      double draw = static_cast<double>(random_() >> 11) * 0x1.0p-53 * total;
      std::size_t chosen = members.size() - 1;
      for (std::size_t i = 0; i < members.size(); ++i) {
        draw -= nearest[i];
        if (draw < 0.0 && nearest[i] > 0.0) {
          chosen = i;
          break;
        }
      }
      centres.push_back(descriptors_[members[chosen]]);
    }
    return centres;
  }

  /// Nearest centre per member (ties to the lower index); true when any assignment changed.
  bool assign(const std::vector<std::uint32_t>& members, const std::vector<BinaryDescriptor>& centres,
              std::vector<std::uint32_t>& assignment) const {
    bool changed = false;
    for (std::size_t i = 0; i < members.size(); ++i) {
      std::uint32_t best = 0;
      int best_distance = std::numeric_limits<int>::max();
      for (std::uint32_t c = 0; c < centres.size(); ++c) {
        const int d = hammingDistance(descriptors_[members[i]], centres[c]);
        if (d < best_distance) best_distance = d, best = c;
      }
      changed = changed || assignment[i] != best;
      assignment[i] = best;
    }
    return changed;
  }

  /// Each centre's bit is set where more than half of its members have it (k-majority, DBoW2's
  /// "median" of binary descriptors); a centre without members keeps its place.
  std::vector<BinaryDescriptor> majorityCentres(const std::vector<std::uint32_t>& members,
                                                const std::vector<std::uint32_t>& assignment,
                                                const std::vector<BinaryDescriptor>& previous) const {
    std::vector<std::array<std::uint32_t, 256>> ones(previous.size());
    std::vector<std::uint32_t> counts(previous.size(), 0);
    for (auto& o : ones) o.fill(0);
    for (std::size_t i = 0; i < members.size(); ++i) {
      const BinaryDescriptor& d = descriptors_[members[i]];
      auto& o = ones[assignment[i]];
      ++counts[assignment[i]];
      for (int bit = 0; bit < 256; ++bit) o[bit] += (d[bit / 64] >> (bit % 64)) & 1u;
    }
    std::vector<BinaryDescriptor> centres = previous;
    for (std::size_t c = 0; c < centres.size(); ++c) {
      if (counts[c] == 0) continue;
      BinaryDescriptor centre{};
      for (int bit = 0; bit < 256; ++bit)
        if (2 * ones[c][bit] > counts[c]) centre[bit / 64] |= std::uint64_t{1} << (bit % 64);
      centres[c] = centre;
    }
    return centres;
  }

  const std::vector<BinaryDescriptor>& descriptors_;
  const VocabularyTrainingOptions& options_;
  BinaryVocabulary& vocabulary_;
  std::mt19937_64 random_;  // fully specified by the standard: the same tree everywhere
};

BinaryVocabulary BinaryVocabulary::train(const std::vector<cv::Mat>& images, const VocabularyTrainingOptions& options) {
  if (options.branching < 2 || options.depth < 1 || options.max_iterations < 1)
    throw std::invalid_argument("vocabulary training: need branching >= 2, depth >= 1 and max_iterations >= 1");
  std::vector<BinaryDescriptor> all;
  std::vector<std::size_t> image_end;
  for (const cv::Mat& image : images) {
    const auto rows = toBinaryDescriptors(image);
    all.insert(all.end(), rows.begin(), rows.end());
    image_end.push_back(all.size());
  }
  if (all.empty()) throw std::invalid_argument("vocabulary training: no descriptors in the training images");

  BinaryVocabulary vocabulary;
  vocabulary.branching_ = options.branching;
  vocabulary.depth_ = options.depth;
  vocabulary.nodes_.push_back({});
  std::vector<std::uint32_t> members(all.size());
  for (std::uint32_t i = 0; i < members.size(); ++i) members[i] = i;
  Trainer(all, options, vocabulary).grow(0, members, 0);
  if (vocabulary.nodes_.size() == 1) {  // too few descriptors to split: one word holding them all
    vocabulary.nodes_.push_back({all.front(), {}, 0});
    vocabulary.nodes_[0].children.push_back(1);
  }
  for (std::uint32_t n = 1; n < vocabulary.nodes_.size(); ++n)
    if (vocabulary.nodes_[n].children.empty()) {
      vocabulary.nodes_[n].word = static_cast<WordId>(vocabulary.words_.size());
      vocabulary.words_.push_back(n);
    }

  // Inverse document frequency over the training images.
  std::vector<std::size_t> documents(vocabulary.words_.size(), 0);
  std::size_t begin = 0;
  for (std::size_t end : image_end) {
    std::vector<WordId> seen;
    for (std::size_t i = begin; i < end; ++i) seen.push_back(vocabulary.wordOf(all[i]));
    std::sort(seen.begin(), seen.end());
    seen.erase(std::unique(seen.begin(), seen.end()), seen.end());
    for (WordId w : seen) ++documents[w];
    begin = end;
  }
  const double n_images = static_cast<double>(images.size());
  for (std::size_t w = 0; w < documents.size(); ++w)
    vocabulary.weights_.push_back(std::log(n_images / static_cast<double>(std::max<std::size_t>(documents[w], 1))));
  return vocabulary;
}

// --- Use.

double BinaryVocabulary::weight(WordId word) const {
  if (word >= weights_.size())
    throw std::out_of_range("vocabulary: word " + std::to_string(word) + " of " + std::to_string(weights_.size()));
  return weights_[word];
}

WordId BinaryVocabulary::wordOf(const BinaryDescriptor& descriptor) const {
  std::uint32_t node = 0;
  while (!nodes_[node].children.empty()) {
    std::uint32_t best = nodes_[node].children.front();
    int best_distance = std::numeric_limits<int>::max();
    for (std::uint32_t child : nodes_[node].children) {
      const int d = hammingDistance(descriptor, nodes_[child].centre);
      if (d < best_distance) best_distance = d, best = child;
    }
    node = best;
  }
  return nodes_[node].word;
}

BowVector BinaryVocabulary::transform(const cv::Mat& descriptors) const {
  BowVector bow;
  for (const BinaryDescriptor& d : toBinaryDescriptors(descriptors)) bow[wordOf(d)] += 1.0;  // term counts
  // tf * idf, tf's denominator cancelling in the normalisation; the weights are scaled by the largest first, which
  // the normalisation cancels too, so that no sum overflows whatever weights a loaded file holds.
  double largest = 0.0;
  for (const auto& [word, count] : bow) largest = std::max(largest, weights_[word]);
  double sum = 0.0;
  if (largest > 0.0)
    for (auto& [word, value] : bow) sum += (value *= weights_[word] / largest);
  if (sum > 0.0)
    for (auto& [word, value] : bow) value /= sum;
  else
    bow.clear();  // only words of weight 0 (seen in every training image): nothing to tell places apart
  return bow;
}

double BinaryVocabulary::score(const BowVector& a, const BowVector& b) {
  // Over the common words only: |a - b|_1 = 2 - sum(|a_i| + |b_i| - |a_i - b_i|) for L1-normalised vectors.
  double common = 0.0;
  auto i = a.begin();
  auto j = b.begin();
  while (i != a.end() && j != b.end()) {
    if (i->first < j->first) {
      ++i;
    } else if (j->first < i->first) {
      ++j;
    } else {
      common += std::abs(i->second) + std::abs(j->second) - std::abs(i->second - j->second);
      ++i, ++j;
    }
  }
  return std::clamp(0.5 * common, 0.0, 1.0);
}

// --- The text format.

void BinaryVocabulary::write(std::ostream& out) const {
  out << "# weighted_icp binary vocabulary: a DBoW2-style tree over 256-bit ORB descriptors\n"
      << "# (docs/place_recognition.md). One node per line below the root, parents first:\n"
      << "# node <parent index, root 0> <leaf 0|1> <IDF weight, leaves> <descriptor, 64 hex digits>\n";
  out << kMagic << ' ' << kFormatVersion << '\n'
      << "branching " << branching_ << '\n'
      << "depth " << depth_ << '\n'
      << "nodes " << nodes_.size() - 1 << '\n';
  std::vector<std::uint32_t> parent(nodes_.size(), 0);
  for (std::uint32_t n = 0; n < nodes_.size(); ++n)
    for (std::uint32_t child : nodes_[n].children) parent[child] = n;
  out << std::setprecision(17);
  for (std::uint32_t n = 1; n < nodes_.size(); ++n) {
    const Node& node = nodes_[n];
    const bool leaf = node.children.empty();
    out << "node " << parent[n] << ' ' << (leaf ? 1 : 0) << ' ' << (leaf ? weights_[node.word] : 0.0) << ' ';
    const auto* bytes = reinterpret_cast<const unsigned char*>(node.centre.data());
    static const char* kHex = "0123456789abcdef";
    for (int b = 0; b < kDescriptorBytes; ++b) out << kHex[bytes[b] >> 4] << kHex[bytes[b] & 15];
    out << '\n';
  }
  if (!out) throw std::runtime_error("vocabulary: writing failed");
}

namespace {

/// Reads the format line by line, naming the source and line in every error.
class VocabularyReader {
 public:
  VocabularyReader(std::istream& in, const std::string& name) : in_(in), name_(name) {}

  std::size_t line() const { return line_number_; }

  [[noreturn]] void fail(const std::string& what) const {
    throw std::runtime_error(name_ + ":" + std::to_string(line_number_) + ": " + what);
  }

  /// The next line that is neither blank nor a comment, split into words; false at the end.
  bool next(std::vector<std::string>& words) {
    std::string line;
    while (std::getline(in_, line)) {
      ++line_number_;
      const auto first = line.find_first_not_of(" \t\r");
      if (first == std::string::npos || line[first] == '#') continue;
      std::istringstream fields(line);
      words.clear();
      for (std::string word; fields >> word;) words.push_back(word);
      return true;
    }
    if (in_.bad()) fail("read error");
    ++line_number_;
    return false;
  }

  unsigned long long integer(const std::string& text, const std::string& what) const {
    std::size_t used = 0;
    unsigned long long value = 0;
    try {
      if (text.empty() || text[0] == '-') throw std::invalid_argument(text);
      value = std::stoull(text, &used);
    } catch (const std::exception&) {
      fail(what + " must be a non-negative integer, got " + detail::echo(text));
    }
    if (used != text.size()) fail(what + " must be a non-negative integer, got " + detail::echo(text));
    return value;
  }

  double real(const std::string& text, const std::string& what) const {
    std::size_t used = 0;
    double value = 0.0;
    try {
      value = std::stod(text, &used);
    } catch (const std::exception&) {
      fail(what + " must be a number, got " + detail::echo(text));
    }
    if (used != text.size() || !std::isfinite(value) || value < 0.0)
      fail(what + " must be a finite number >= 0, got " + detail::echo(text));
    return value;
  }

  /// "key value" header line.
  unsigned long long header(const std::string& key) {
    std::vector<std::string> words;
    if (!next(words)) fail("unexpected end of file: expected '" + key + " <value>'");
    if (words.size() != 2 || words[0] != key) fail("expected '" + key + " <value>'");
    return integer(words[1], key);
  }

  BinaryDescriptor descriptor(const std::string& hex) const {
    if (hex.size() != 2 * kDescriptorBytes)
      fail("descriptor must have 64 hex digits, got " + std::to_string(hex.size()));
    BinaryDescriptor d{};
    auto* bytes = reinterpret_cast<unsigned char*>(d.data());
    for (int b = 0; b < kDescriptorBytes; ++b) {
      int value = 0;
      for (int h = 0; h < 2; ++h) {
        const char c = hex[2 * b + h];
        const int digit = c >= '0' && c <= '9'   ? c - '0'
                          : c >= 'a' && c <= 'f' ? c - 'a' + 10
                          : c >= 'A' && c <= 'F' ? c - 'A' + 10
                                                 : -1;
        if (digit < 0) fail("descriptor has a character that is not a hex digit: " + detail::echo(std::string(1, c)));
        value = 16 * value + digit;
      }
      bytes[b] = static_cast<unsigned char>(value);
    }
    return d;
  }

 private:
  std::istream& in_;
  std::string name_;
  std::size_t line_number_ = 0;
};

}  // namespace

BinaryVocabulary BinaryVocabulary::read(std::istream& in, const std::string& name) {
  VocabularyReader reader(in, name);
  std::vector<std::string> words;
  if (!reader.next(words)) reader.fail("empty file: not a vocabulary");
  if (words.size() != 2 || words[0] != kMagic) reader.fail("not a vocabulary: expected 'wicp_vocabulary 1'");
  if (reader.integer(words[1], "format version") != kFormatVersion)
    reader.fail("unsupported format version " + detail::echo(words[1]) + " (this build reads 1)");
  BinaryVocabulary vocabulary;
  const auto branching = reader.header("branching");
  if (branching < 2 || branching > 1000) reader.fail("branching must be in [2, 1000]");
  const auto depth = reader.header("depth");
  if (depth < 1 || depth > 32) reader.fail("depth must be in [1, 32]");
  const auto count = reader.header("nodes");
  if (count < 1 || count > 100'000'000) reader.fail("nodes must be in [1, 100000000]");
  vocabulary.branching_ = static_cast<unsigned int>(branching);
  vocabulary.depth_ = static_cast<unsigned int>(depth);
  vocabulary.nodes_.push_back({});
  std::vector<unsigned int> level(1, 0);
  std::vector<bool> is_leaf(1, false);
  std::vector<std::size_t> node_line(1, 0);
  for (unsigned long long n = 1; n <= count; ++n) {
    if (!reader.next(words))
      reader.fail("unexpected end of file: " + std::to_string(count) + " nodes declared, " + std::to_string(n - 1) +
                  " found");
    if (words.size() != 5 || words[0] != "node")
      reader.fail("expected 'node <parent> <leaf 0|1> <weight> <descriptor>'");
    const auto parent = reader.integer(words[1], "parent");
    if (parent >= n)
      reader.fail("parent " + detail::echo(words[1]) + " is not an earlier node (nodes are listed parents first)");
    if (is_leaf[parent]) reader.fail("parent " + detail::echo(words[1]) + " is a leaf");
    if (vocabulary.nodes_[parent].children.size() >= branching)
      reader.fail("node " + detail::echo(words[1]) + " has more than branching = " + std::to_string(branching) +
                  " children");
    if (level[parent] + 1 > depth) reader.fail("node is deeper than depth = " + std::to_string(depth));
    const auto leaf = reader.integer(words[2], "leaf flag");
    if (leaf > 1) reader.fail("leaf flag must be 0 or 1, got " + detail::echo(words[2]));
    const double weight = reader.real(words[3], "weight");
    Node node{reader.descriptor(words[4]), {}, 0};
    if (leaf) {
      node.word = static_cast<WordId>(vocabulary.words_.size());
      vocabulary.words_.push_back(static_cast<std::uint32_t>(n));
      vocabulary.weights_.push_back(weight);
    }
    vocabulary.nodes_[parent].children.push_back(static_cast<std::uint32_t>(n));
    vocabulary.nodes_.push_back(node);
    level.push_back(level[parent] + 1);
    is_leaf.push_back(leaf == 1);
    node_line.push_back(reader.line());
  }
  if (reader.next(words)) reader.fail("more nodes than the " + std::to_string(count) + " declared");
  for (std::size_t n = 1; n < vocabulary.nodes_.size(); ++n)
    if (!is_leaf[n] && vocabulary.nodes_[n].children.empty())
      throw std::runtime_error(name + ":" + std::to_string(node_line[n]) + ": node " + std::to_string(n) +
                               " is not a leaf (flag 0) but no node names it as parent");
  return vocabulary;
}

BinaryVocabulary BinaryVocabulary::load(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open the vocabulary file");
  return read(in, path);
}

}  // namespace weighted_icp::mapping
