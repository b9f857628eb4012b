#include "weighted_icp/frontend/perception/descriptor_matcher.h"

#include <algorithm>
#include <stdexcept>

#include <opencv2/flann.hpp>

#include "weighted_icp/core/binary_descriptor.h"
#include "weighted_icp/core/named_values.h"
#include "weighted_icp/core/parallel_for.h"

namespace weighted_icp::frontend {
namespace {

void requireOption(bool valid, const std::string& what) {
  if (!valid) throw std::invalid_argument("DescriptorMatcher: " + what);
}

void requireBinary(const cv::Mat& descriptors, const char* role) {
  if (!descriptors.empty() && descriptors.type() != CV_8UC1)
    throw std::invalid_argument(std::string("DescriptorMatcher: ") + role +
                                " descriptors must be CV_8UC1 (binary), got type " +
                                cv::typeToString(descriptors.type()));
}

cv::Ptr<cv::DescriptorMatcher> buildMatcher(const DescriptorMatcherOptions& o, const cv::Mat& reference) {
  cv::Ptr<cv::DescriptorMatcher> matcher;
  if (o.kind == MatcherKind::BruteForce) {
    matcher = cv::makePtr<cv::BFMatcher>(cv::NORM_HAMMING);
  } else {
    matcher = cv::makePtr<cv::FlannBasedMatcher>(
        cv::makePtr<cv::flann::LshIndexParams>(o.lsh_tables, o.lsh_key_bits, o.lsh_multi_probe_level));
  }
  matcher->add(std::vector<cv::Mat>{reference});
  // FLANN draws the LSH key bits from the calling thread's cv::theRNG(); a
  // fixed seed, restored afterwards, makes the index the same on every build.
  cv::RNG& rng = cv::theRNG();
  const cv::RNG saved = rng;
  rng = cv::RNG(o.lsh_seed);
  try {
    matcher->train();
  } catch (...) {
    rng = saved;
    throw;
  }
  rng = saved;
  return matcher;
}

// Query rows per parallel job: each row's search is independent of the others,
// so any split gives the same nearest pairs; 128 rows keep a job's cost (about
// 1 ms with LSH on a 2000-row local map) well above the pool's overhead.
constexpr int kQueryRowsPerJob = 128;

// Rows of this length (ORB's and the modified BRIEF's 256 bits) are searched as
// BinaryDescriptors by the brute-force matcher; other lengths by OpenCV's.
constexpr int kWordRowBytes = static_cast<int>(sizeof(BinaryDescriptor));

/// Runs step(first, last) over query rows [0, rows) in jobs of kQueryRowsPerJob on the thread pool. Each row's
/// search only reads the index and writes its own row of the result, so any split gives the same result.
template <typename Step>
void forEachQueryJob(int rows, const Step& step) {
  const int jobs = (rows + kQueryRowsPerJob - 1) / kQueryRowsPerJob;
  parallelFor(cv::Range(0, jobs), [&](const cv::Range& range) {
    for (int job = range.start; job < range.end; ++job)
      step(job * kQueryRowsPerJob, std::min(rows, (job + 1) * kQueryRowsPerJob));
  });
}

/// The matcher's LSH parameters as our index takes them.
BinaryLshOptions lshOptions(const DescriptorMatcherOptions& o) {
  return {o.lsh_tables, o.lsh_key_bits, o.lsh_multi_probe_level, o.lsh_seed};
}

/// One search's two nearest as knnMatch's pair for query row q; empty without a second (no ratio test possible).
std::vector<cv::DMatch> asNearestPair(int q, const TwoNearest& two) {
  if (two.second < 0) return {};
  return {cv::DMatch(q, two.best, static_cast<float>(two.best_distance)),
          cv::DMatch(q, two.second, static_cast<float>(two.second_distance))};
}

}  // namespace

DescriptorMatcher::DescriptorMatcher(DescriptorMatcherOptions options) : options_(options) {
  requireOption(options_.ratio > 0.0f && options_.ratio <= 1.0f, "ratio must be in (0, 1]");
  requireOption(options_.max_hamming_distance >= 0, "max_hamming_distance must be >= 0");
  requireOption(options_.lsh_tables >= 1, "lsh_tables must be >= 1");
  requireOption(options_.lsh_key_bits >= 1 && options_.lsh_key_bits <= 32, "lsh_key_bits must be in [1, 32]");
  requireOption(options_.lsh_multi_probe_level >= 0, "lsh_multi_probe_level must be >= 0");
  if (options_.kind == MatcherKind::Lsh)  // our index's own limits (key bits up to 24, probes up to 2 bits away)
    BinaryLshIndex::validate(lshOptions(options_));
  requireOption(options_.kd_tree.leaf_size >= 1, "kd_tree.leaf_size must be >= 1");
  requireOption(options_.kd_tree.max_backtracks >= 0, "kd_tree.max_backtracks must be >= 0");
}

void DescriptorMatcher::setReference(const cv::Mat& descriptors) {
  requireBinary(descriptors, "reference");
  matcher_.release();
  kd_tree_.reset();
  lsh_.reset();
  reference_words_.clear();
  reference_rows_ = descriptors.empty() ? 0 : descriptors.rows;
  reference_cols_ = descriptors.empty() ? 0 : descriptors.cols;
  if (reference_rows_ == 0) return;
  if (options_.kind == MatcherKind::BruteForce && reference_cols_ == kWordRowBytes) {
    reference_words_ = toBinaryDescriptors(descriptors);
  } else if (options_.kind == MatcherKind::Lsh) {
    lsh_ = std::make_shared<BinaryLshIndex>(lshOptions(options_));
    lsh_->build(descriptors);
  } else if (options_.kind == MatcherKind::KdTree) {
    kd_tree_ = std::make_shared<BinaryKdTree>(options_.kd_tree);
    kd_tree_->build(descriptors);
  } else {
    matcher_ = buildMatcher(options_, descriptors);
  }
}

std::vector<cv::DMatch> DescriptorMatcher::match(const cv::Mat& query) const {
  requireBinary(query, "query");
  if (query.empty() || reference_rows_ == 0) return {};
  if (query.cols != reference_cols_)
    throw std::invalid_argument("DescriptorMatcher: query rows have " + std::to_string(query.cols) +
                                " bytes, reference rows " + std::to_string(reference_cols_));
  if (reference_rows_ < 2) return {};  // no second nearest for the ratio test

  const std::vector<std::vector<cv::DMatch>> nearest = nearestTwo(query);
  std::vector<cv::DMatch> matches;
  for (const std::vector<cv::DMatch>& candidates : nearest) {
    if (candidates.size() < 2) continue;
    const cv::DMatch& best = candidates[0];
    if (best.distance < options_.ratio * candidates[1].distance &&
        best.distance <= static_cast<float>(options_.max_hamming_distance))
      matches.push_back(best);
  }

  if (options_.cross_check_unique) matches = keepBestMatchPerReference(matches, reference_rows_);
  return matches;  // knnMatch returns one list per query row, in order
}

std::vector<std::vector<cv::DMatch>> DescriptorMatcher::nearestTwo(const cv::Mat& query) const {
  if (!reference_words_.empty()) return exhaustiveNearestTwo(query);
  std::vector<std::vector<cv::DMatch>> nearest(static_cast<std::size_t>(query.rows));
  // The searches only read the index (our LSH and KD-tree and FLANN's LSH k-NN search keep no state between
  // queries; the OpenCV matcher's train() is a no-op once trained), so jobs share it.
  forEachQueryJob(query.rows, [&](int first, int last) {
    if (lsh_) {
      BinaryLshIndex::Scratch scratch;  // one per job: jobs run concurrently
      for (int q = first; q < last; ++q)
        nearest[static_cast<std::size_t>(q)] = asNearestPair(q, lsh_->nearestTwo(query.ptr<std::uint8_t>(q), scratch));
    } else if (kd_tree_) {
      for (int q = first; q < last; ++q)
        nearest[static_cast<std::size_t>(q)] = asNearestPair(q, kd_tree_->nearestTwo(query.ptr<std::uint8_t>(q)));
    } else {
      std::vector<std::vector<cv::DMatch>> rows;
      matcher_->knnMatch(query.rowRange(first, last), rows, 2);
      for (std::size_t r = 0; r < rows.size(); ++r) {
        for (cv::DMatch& m : rows[r]) m.queryIdx += first;  // chunk row -> query row
        nearest[static_cast<std::size_t>(first) + r] = std::move(rows[r]);
      }
    }
  });
  return nearest;
}

std::vector<std::vector<cv::DMatch>> DescriptorMatcher::exhaustiveNearestTwo(const cv::Mat& query) const {
  const std::vector<BinaryDescriptor> words = toBinaryDescriptors(query);
  std::vector<std::vector<cv::DMatch>> nearest(words.size());
  forEachQueryJob(query.rows, [&](int first, int last) {
    for (int q = first; q < last; ++q) {
      const NearestTwo two = weighted_icp::nearestTwo(words[static_cast<std::size_t>(q)], reference_words_);
      nearest[static_cast<std::size_t>(q)] = {
          cv::DMatch(q, static_cast<int>(two.index), static_cast<float>(two.best)),
          cv::DMatch(q, static_cast<int>(two.second_index), static_cast<float>(two.second))};
    }
  });
  return nearest;
}

std::vector<cv::DMatch> keepBestMatchPerReference(const std::vector<cv::DMatch>& matches, int reference_rows) {
  std::vector<int> winner(static_cast<std::size_t>(reference_rows), -1);
  for (int i = 0; i < static_cast<int>(matches.size()); ++i) {
    int& current = winner[static_cast<std::size_t>(matches[i].trainIdx)];
    if (current < 0 || matches[i].distance < matches[current].distance) current = i;
  }
  std::vector<cv::DMatch> unique;
  for (int i = 0; i < static_cast<int>(matches.size()); ++i)
    if (winner[static_cast<std::size_t>(matches[i].trainIdx)] == i) unique.push_back(matches[i]);
  return unique;
}

MatcherKind parseMatcherKind(const std::string& name) {
  return parseNamedValue(name, {MatcherKind::FlannLsh, MatcherKind::BruteForce, MatcherKind::KdTree, MatcherKind::Lsh},
                         matcherKindName, "matcher");
}

std::string matcherKindName(MatcherKind kind) {
  switch (kind) {
    case MatcherKind::FlannLsh: return "flann";
    case MatcherKind::BruteForce: return "brute-force";
    case MatcherKind::KdTree: return "kd-tree";
    case MatcherKind::Lsh: return "lsh";
  }
  return "unknown";
}

}  // namespace weighted_icp::frontend
