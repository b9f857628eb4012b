// BinaryLshIndex (our LSH over binary descriptors): near copies always found, answers are true distances of real
// rows and never nearer than the exact nearest, deterministic for a seed, checked options and inputs; and the
// matcher built on it agrees with exact search on most real matches, whatever the number of threads.

#include <random>
#include <set>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "test_perception_support.h"
#include "test_support.h"
#include "weighted_icp/core/binary_descriptor.h"
#include "weighted_icp/frontend/perception/binary_lsh_index.h"
#include "weighted_icp/frontend/perception/descriptor_matcher.h"
#include "weighted_icp/frontend/perception/feature_extractor.h"

namespace {

using namespace weighted_icp::frontend;
using weighted_icp::hammingDistance;

cv::Mat randomRows(int rows, int bytes, unsigned seed) {
  cv::Mat d(rows, bytes, CV_8UC1);
  std::mt19937 random(seed);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < bytes; ++c) d.at<std::uint8_t>(r, c) = static_cast<std::uint8_t>(random() & 0xff);
  return d;
}

cv::Mat nearCopy(const cv::Mat& row, int bits, unsigned seed) {
  cv::Mat copy = row.clone();
  std::mt19937 random(seed);
  for (int i = 0; i < bits; ++i) {
    const int b = static_cast<int>(random() % (8 * row.cols));
    copy.at<std::uint8_t>(0, b / 8) ^= static_cast<std::uint8_t>(1u << (b % 8));
  }
  return copy;
}

int distance(const cv::Mat& a, int row_a, const cv::Mat& b, int row_b) {
  return hammingDistance(a.ptr(row_a), b.ptr(row_b), a.cols);
}

TEST(BinaryLshIndex, FindsNearCopiesAndAnswersWithTrueDistances) {
  const cv::Mat reference = randomRows(1500, 32, 1);
  BinaryLshIndex index;
  index.build(reference);
  BinaryLshIndex::Scratch scratch;
  for (int q = 0; q < 100; ++q) {
    const int row = (q * 13) % reference.rows;
    const cv::Mat query = nearCopy(reference.row(row), q % 9, 100 + q);  // 0-8 bits away: in a probed bucket
    const TwoNearest two = index.nearestTwo(query.ptr(), scratch);
    ASSERT_EQ(two.best, row) << "query " << q;
    EXPECT_EQ(two.best_distance, distance(query, 0, reference, row));
    if (two.second >= 0) {  // whatever else was found: a real row at its true distance, not nearer than the best
      EXPECT_EQ(two.second_distance, distance(query, 0, reference, two.second));
      EXPECT_GE(two.second_distance, two.best_distance);
    }
  }
}

TEST(BinaryLshIndex, NeverAnswersNearerThanTheExactNearest) {
  const cv::Mat reference = randomRows(800, 32, 2);
  const cv::Mat queries = randomRows(200, 32, 3);  // far from everything: few or no candidates
  BinaryLshIndex index;
  index.build(reference);
  BinaryLshIndex::Scratch scratch;
  int answered = 0;
  for (int q = 0; q < queries.rows; ++q) {
    int exact = 1 << 30;
    for (int r = 0; r < reference.rows; ++r) exact = std::min(exact, distance(queries, q, reference, r));
    const TwoNearest two = index.nearestTwo(queries.ptr(q), scratch);
    if (two.best < 0) continue;
    ++answered;
    EXPECT_GE(two.best_distance, exact);
    EXPECT_EQ(two.best_distance, distance(queries, q, reference, two.best));
  }
  EXPECT_GT(answered, 0);
}

TEST(BinaryLshIndex, SameSeedSameAnswersAnyScratch) {
  const cv::Mat reference = randomRows(1000, 32, 4);
  const cv::Mat queries = randomRows(300, 32, 5);
  BinaryLshIndex a, b, other_seed(BinaryLshOptions{8, 14, 1, 42});
  a.build(reference), b.build(reference), other_seed.build(reference);
  BinaryLshIndex::Scratch shared, fresh;
  bool seed_matters = false;
  for (int q = 0; q < queries.rows; ++q) {
    const TwoNearest x = a.nearestTwo(queries.ptr(q), shared);
    BinaryLshIndex::Scratch one_off;
    const TwoNearest y = b.nearestTwo(queries.ptr(q), q % 2 ? fresh : one_off);
    EXPECT_EQ(x.best, y.best);
    EXPECT_EQ(x.second, y.second);
    const TwoNearest z = other_seed.nearestTwo(queries.ptr(q), shared);  // a scratch sized for another index
    seed_matters = seed_matters || z.best != x.best || z.second != x.second;
  }
  EXPECT_TRUE(seed_matters) << "another seed samples other bits";
}

TEST(BinaryLshIndex, FewRowsAndOtherRowLengths) {
  BinaryLshIndex index;
  BinaryLshIndex::Scratch scratch;
  const cv::Mat query = randomRows(1, 32, 6);
  EXPECT_EQ(index.nearestTwo(query.ptr(), scratch).best, -1) << "not built";
  index.build(cv::Mat());
  EXPECT_EQ(index.nearestTwo(query.ptr(), scratch).best, -1) << "built on nothing";
  index.build(query);
  const TwoNearest one = index.nearestTwo(query.ptr(), scratch);
  EXPECT_EQ(one.best, 0);
  EXPECT_EQ(one.second, -1);
  // 64-byte rows (any length of at least key_bits bits).
  const cv::Mat long_rows = randomRows(300, 64, 7);
  index.build(long_rows);
  const cv::Mat near = nearCopy(long_rows.row(17), 5, 8);
  EXPECT_EQ(index.nearestTwo(near.ptr(), scratch).best, 17);
}

TEST(BinaryLshIndex, RefusesBadOptionsAndInputs) {
  EXPECT_THROW(BinaryLshIndex(BinaryLshOptions{0, 14, 1, 1}), std::invalid_argument);
  EXPECT_THROW(BinaryLshIndex(BinaryLshOptions{8, 0, 1, 1}), std::invalid_argument);
  EXPECT_THROW(BinaryLshIndex(BinaryLshOptions{8, 25, 1, 1}), std::invalid_argument);
  EXPECT_THROW(BinaryLshIndex(BinaryLshOptions{8, 14, 3, 1}), std::invalid_argument);
  BinaryLshIndex index;
  EXPECT_THROW(index.build(cv::Mat(10, 32, CV_32F, cv::Scalar(0))), std::invalid_argument);
  EXPECT_THROW(index.build(cv::Mat(10, 1, CV_8U, cv::Scalar(0))), std::invalid_argument) << "8 bits < 14-bit keys";
  DescriptorMatcherOptions options;
  options.kind = MatcherKind::Lsh;
  options.lsh_key_bits = 30;  // FLANN's index takes it, ours does not
  EXPECT_THROW(DescriptorMatcher{options}, std::invalid_argument);
  EXPECT_EQ(parseMatcherKind("lsh"), MatcherKind::Lsh);
  EXPECT_EQ(matcherKindName(MatcherKind::Lsh), "lsh");
}

// On real frames: most exact matches found, the same matches with one thread or the pool.
TEST(BinaryLshIndex, MatcherFindsMostExactMatchesOnRealFramesWithAnyThreads) {
  namespace t = weighted_icp::testing;
  WEIGHTED_ICP_REQUIRE_FILE(t::tumHeadDir(1) / "rgb.txt");
  const auto sequence = t::RealSequence::open(t::tumHeadDir(1), 1);
  const cv::Mat reference = FeatureExtractor().extract(sequence.frame(0).gray()).descriptors;
  const cv::Mat query = FeatureExtractor().extract(sequence.frame(5).gray()).descriptors;
  DescriptorMatcherOptions options;
  options.kind = MatcherKind::BruteForce;
  DescriptorMatcher exact_matcher(options);
  exact_matcher.setReference(reference);
  const std::vector<cv::DMatch> exact = exact_matcher.match(query);
  options.kind = MatcherKind::Lsh;
  DescriptorMatcher lsh_matcher(options);
  lsh_matcher.setReference(reference);
  const std::vector<cv::DMatch> lsh = lsh_matcher.match(query);
  std::set<std::pair<int, int>> found;
  for (const cv::DMatch& m : lsh) found.insert({m.queryIdx, m.trainIdx});
  std::size_t shared = 0;
  for (const cv::DMatch& m : exact) shared += found.count({m.queryIdx, m.trainIdx});
  ASSERT_GE(exact.size(), 150u);
  EXPECT_GE(static_cast<double>(shared), 0.8 * static_cast<double>(exact.size())) << shared << " of " << exact.size();

  const int threads = cv::getNumThreads();
  cv::setNumThreads(1);
  const std::vector<cv::DMatch> serial = lsh_matcher.match(query);
  cv::setNumThreads(threads);
  ASSERT_EQ(serial.size(), lsh.size());
  for (std::size_t i = 0; i < lsh.size(); ++i) {
    EXPECT_EQ(serial[i].queryIdx, lsh[i].queryIdx);
    EXPECT_EQ(serial[i].trainIdx, lsh[i].trainIdx);
  }
}

}  // namespace
