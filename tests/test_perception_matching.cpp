// Descriptor matching on consecutive real TUM frames: FLANN LSH finds most of
// what brute force finds, the ratio test and distance cap hold, the matches
// agree with the ground-truth motion, and results are reproducible.

#include <algorithm>
#include <iostream>
#include <map>
#include <set>
#include <thread>

#include <gtest/gtest.h>

#include "test_perception_support.h"
#include "test_support.h"
#include "weighted_icp/frontend/perception/descriptor_matcher.h"
#include "weighted_icp/frontend/perception/feature_extractor.h"

namespace {

using namespace weighted_icp;
using frontend::DescriptorMatcher;
using frontend::DescriptorMatcherOptions;
using frontend::ExtractedFeatures;
using frontend::MatcherKind;
using weighted_icp::testing::RealSequence;

struct FramePair {
  int freiburg;
  std::size_t reference, query;
};

std::string pairName(const FramePair& p) {
  return "fr" + std::to_string(p.freiburg) + "_" + std::to_string(p.reference) + "_to_" + std::to_string(p.query);
}

const RealSequence& sequence(int freiburg) {
  static const RealSequence fr1 = RealSequence::open(weighted_icp::testing::tumHeadDir(1), 1);
  static const RealSequence fr3 = RealSequence::open(weighted_icp::testing::tumHeadDir(3), 3);
  return freiburg == 1 ? fr1 : fr3;
}

const ExtractedFeatures& features(int freiburg, std::size_t frame) {
  static std::map<std::pair<int, std::size_t>, ExtractedFeatures> cache;
  auto it = cache.find({freiburg, frame});
  if (it == cache.end())
    it = cache
             .emplace(std::make_pair(freiburg, frame),
                      frontend::FeatureExtractor().extract(sequence(freiburg).frame(frame).gray()))
             .first;
  return it->second;
}

std::vector<cv::DMatch> matchPair(const FramePair& p, DescriptorMatcherOptions options) {
  DescriptorMatcher matcher(options);
  matcher.setReference(features(p.freiburg, p.reference).descriptors);
  return matcher.match(features(p.freiburg, p.query).descriptors);
}

DescriptorMatcherOptions withKind(MatcherKind kind) {
  DescriptorMatcherOptions options;
  options.kind = kind;
  return options;
}

bool sameMatches(const std::vector<cv::DMatch>& a, const std::vector<cv::DMatch>& b) {
  return std::equal(a.begin(), a.end(), b.begin(), b.end(), [](const cv::DMatch& x, const cv::DMatch& y) {
    return x.queryIdx == y.queryIdx && x.trainIdx == y.trainIdx && x.distance == y.distance;
  });
}

class RealFramePair : public ::testing::TestWithParam<FramePair> {
 protected:
  void SetUp() override {
    WEIGHTED_ICP_REQUIRE_FILE(weighted_icp::testing::tumHeadDir(GetParam().freiburg) / "groundtruth.txt");
  }
};

TEST_P(RealFramePair, LshFindsMostBruteForceMatches) {
  const std::vector<cv::DMatch> exact = matchPair(GetParam(), withKind(MatcherKind::BruteForce));
  const std::vector<cv::DMatch> lsh = matchPair(GetParam(), withKind(MatcherKind::FlannLsh));
  std::set<std::pair<int, int>> found;
  for (const cv::DMatch& m : lsh) found.insert({m.queryIdx, m.trainIdx});
  const auto shared = std::count_if(exact.begin(), exact.end(), [&](const cv::DMatch& m) {
    return found.count({m.queryIdx, m.trainIdx}) > 0;
  });
  std::cout << pairName(GetParam()) << ": brute force " << exact.size() << " matches, LSH " << lsh.size() << ", "
            << shared << " in both\n";
  ASSERT_GE(exact.size(), 150u);
  EXPECT_GE(static_cast<double>(shared), 0.8 * static_cast<double>(exact.size()));
}

TEST_P(RealFramePair, KeepsTheRatioTestTheCapAndOneMatchPerReference) {
  const cv::Mat& reference = features(GetParam().freiburg, GetParam().reference).descriptors;
  const cv::Mat& query = features(GetParam().freiburg, GetParam().query).descriptors;
  for (const MatcherKind kind : {MatcherKind::BruteForce, MatcherKind::FlannLsh, MatcherKind::Lsh}) {
    DescriptorMatcherOptions options = withKind(kind);
    options.max_hamming_distance = 40;
    const std::vector<cv::DMatch> matches = matchPair(GetParam(), options);
    ASSERT_FALSE(matches.empty());
    std::set<int> references;
    int previous_query = -1;
    for (const cv::DMatch& m : matches) {
      EXPECT_GT(m.queryIdx, previous_query);  // sorted, one per query row
      previous_query = m.queryIdx;
      EXPECT_TRUE(references.insert(m.trainIdx).second) << "reference row " << m.trainIdx << " matched twice";
      const double distance = cv::norm(query.row(m.queryIdx), reference.row(m.trainIdx), cv::NORM_HAMMING);
      EXPECT_EQ(m.distance, distance);
      EXPECT_LE(distance, 40.0);
      if (kind == MatcherKind::BruteForce) {
        // Exact search: the match is the nearest row and clears the ratio
        // test against the true second nearest.
        std::vector<double> all;
        for (int r = 0; r < reference.rows; ++r)
          all.push_back(cv::norm(query.row(m.queryIdx), reference.row(r), cv::NORM_HAMMING));
        std::nth_element(all.begin(), all.begin() + 1, all.end());
        EXPECT_EQ(distance, all[0]);
        EXPECT_LT(distance, options.ratio * all[1]);
      }
    }
  }
}

TEST_P(RealFramePair, MatchesAgreeWithTheGroundTruthMotion) {
  const FramePair p = GetParam();
  for (const MatcherKind kind : {MatcherKind::BruteForce, MatcherKind::FlannLsh, MatcherKind::Lsh}) {
    const std::vector<cv::DMatch> matches = matchPair(p, withKind(kind));
    const auto check = weighted_icp::testing::checkAgainstGroundTruth(
        sequence(p.freiburg), p.reference, p.query, features(p.freiburg, p.reference).keypoints,
        features(p.freiburg, p.query).keypoints, matches, 5.0);
    std::cout << pairName(p) << " " << frontend::matcherKindName(kind) << ": " << check.inliers << " of "
              << check.checked << " matches with depth within 5 px (" << check.fraction() << ")\n";
    EXPECT_GE(check.checked, 150);
    EXPECT_GT(check.fraction(), 0.7);
  }
}

INSTANTIATE_TEST_SUITE_P(Tum, RealFramePair,
                         // fr3's ground truth starts after its first frames.
                         ::testing::Values(FramePair{1, 0, 5}, FramePair{1, 10, 15}, FramePair{3, 10, 15},
                                           FramePair{3, 20, 25}),
                         [](const auto& info) { return pairName(info.param); });

TEST(DescriptorMatcher, LshMatchesDoNotDependOnOpenCvsRandomStateOrThread) {
  const FramePair p{1, 0, 5};
  WEIGHTED_ICP_REQUIRE_FILE(weighted_icp::testing::tumHeadDir(p.freiburg) / "rgb.txt");
  const std::vector<cv::DMatch> first = matchPair(p, withKind(MatcherKind::FlannLsh));
  const uint64 state_before = cv::theRNG().state;
  cv::theRNG().next();  // as any other user of cv::theRNG() would
  const std::vector<cv::DMatch> after_rng_use = matchPair(p, withKind(MatcherKind::FlannLsh));
  EXPECT_NE(cv::theRNG().state, state_before);
  std::vector<cv::DMatch> other_thread;
  std::thread([&] { other_thread = matchPair(p, withKind(MatcherKind::FlannLsh)); }).join();
  EXPECT_TRUE(sameMatches(first, after_rng_use));
  EXPECT_TRUE(sameMatches(first, other_thread));

  // Building the index leaves the caller's random state as it was.
  DescriptorMatcher matcher(withKind(MatcherKind::FlannLsh));
  const uint64 state = cv::theRNG().state;
  matcher.setReference(features(p.freiburg, p.reference).descriptors);
  EXPECT_EQ(cv::theRNG().state, state);
}

// The query is searched in parallel jobs of rows: the matches must be those of
// one search over the whole query (checked for brute force against OpenCV's own
// matcher, whose answer is exact), whatever the number of threads.
TEST(DescriptorMatcher, SearchesInParallelJobsWithTheMatchesOfOneSearch) {
  const FramePair p{1, 0, 5};
  WEIGHTED_ICP_REQUIRE_FILE(weighted_icp::testing::tumHeadDir(p.freiburg) / "rgb.txt");
  const cv::Mat& query = features(p.freiburg, p.query).descriptors;
  const cv::Mat& reference = features(p.freiburg, p.reference).descriptors;
  ASSERT_GT(query.rows, 512) << "the query must span several jobs";

  DescriptorMatcherOptions options = withKind(MatcherKind::BruteForce);
  options.cross_check_unique = false;
  std::vector<std::vector<cv::DMatch>> nearest;
  cv::BFMatcher(cv::NORM_HAMMING).knnMatch(query, reference, nearest, 2);
  std::vector<cv::DMatch> expected;
  for (const std::vector<cv::DMatch>& two : nearest)
    if (two.size() == 2 && two[0].distance < options.ratio * two[1].distance &&
        two[0].distance <= static_cast<float>(options.max_hamming_distance))
      expected.push_back(two[0]);
  ASSERT_GT(expected.size(), 100u);
  const std::vector<cv::DMatch> all = matchPair(p, options);
  EXPECT_TRUE(sameMatches(all, expected)) << all.size() << " vs " << expected.size();
  EXPECT_GT(all.back().queryIdx, 384) << "matches from the last jobs keep their query rows";

  const int threads = cv::getNumThreads();
  for (const MatcherKind kind :
       {MatcherKind::FlannLsh, MatcherKind::BruteForce, MatcherKind::KdTree, MatcherKind::Lsh}) {
    const std::vector<cv::DMatch> pooled = matchPair(p, withKind(kind));
    cv::setNumThreads(1);
    const std::vector<cv::DMatch> serial = matchPair(p, withKind(kind));
    cv::setNumThreads(threads);
    EXPECT_TRUE(sameMatches(pooled, serial)) << frontend::matcherKindName(kind);
  }
}

/// Rows that each differ from one random row in about 16 of 256 bits
/// (seeded): neighbours close enough for LSH to hash some of them together,
/// so that a query has a second nearest for the ratio test.
cv::Mat clusteredDescriptors(int rows, std::uint64_t seed) {
  cv::RNG rng(seed);
  cv::Mat base(1, 32, CV_8U);
  rng.fill(base, cv::RNG::UNIFORM, 0, 256);
  cv::Mat descriptors = cv::repeat(base, rows, 1);
  for (int r = 0; r < rows; ++r)
    for (int flip = 0; flip < 16; ++flip) descriptors.at<std::uint8_t>(r, rng.uniform(0, 32)) ^= 1 << rng.uniform(0, 8);
  return descriptors;
}

TEST(DescriptorMatcher, KeepsOnlyTheBestQueryPerReferenceRow) {
  const cv::Mat reference = clusteredDescriptors(50, 1);
  cv::Mat query(3, 32, CV_8U);
  reference.row(7).copyTo(query.row(0));
  reference.row(7).copyTo(query.row(1));
  query.at<std::uint8_t>(1, 0) ^= 0x01;  // one bit from reference row 7
  reference.row(9).copyTo(query.row(2));
  for (const MatcherKind kind : {MatcherKind::BruteForce, MatcherKind::FlannLsh, MatcherKind::Lsh}) {
    DescriptorMatcherOptions options = withKind(kind);
    options.cross_check_unique = false;
    DescriptorMatcher all(options);
    all.setReference(reference);
    EXPECT_EQ(all.match(query).size(), 3u) << frontend::matcherKindName(kind);

    options.cross_check_unique = true;
    DescriptorMatcher unique(options);
    unique.setReference(reference);
    const std::vector<cv::DMatch> matches = unique.match(query);
    ASSERT_EQ(matches.size(), 2u) << frontend::matcherKindName(kind);
    EXPECT_EQ(matches[0].queryIdx, 0);
    EXPECT_EQ(matches[0].trainIdx, 7);
    EXPECT_EQ(matches[0].distance, 0.0f);
    EXPECT_EQ(matches[1].queryIdx, 2);
    EXPECT_EQ(matches[1].trainIdx, 9);
  }
}

// 256-bit rows are searched by popcount (core/binary_descriptor.h), other row
// lengths by OpenCV's BFMatcher: both must give OpenCV's exact answer.
TEST(DescriptorMatcher, BruteForceOfAnyRowLengthIsOpenCvsExactSearch) {
  for (const int bytes : {32, 16, 64}) {
    cv::Mat reference(300, bytes, CV_8U), query(120, bytes, CV_8U);
    cv::RNG rng(static_cast<std::uint64_t>(bytes));
    rng.fill(reference, cv::RNG::UNIFORM, 0, 256);
    for (int r = 0; r < query.rows; ++r) {  // each query a few bits from a reference row
      reference.row((r * 7) % reference.rows).copyTo(query.row(r));
      for (int flip = 0; flip < 1 + r % 24; ++flip)
        query.at<std::uint8_t>(r, rng.uniform(0, bytes)) ^= 1 << rng.uniform(0, 8);
    }
    DescriptorMatcherOptions options = withKind(MatcherKind::BruteForce);
    options.cross_check_unique = false;
    options.max_hamming_distance = 8 * bytes;
    std::vector<std::vector<cv::DMatch>> nearest;
    cv::BFMatcher(cv::NORM_HAMMING).knnMatch(query, reference, nearest, 2);
    std::vector<cv::DMatch> expected;
    for (const std::vector<cv::DMatch>& two : nearest)
      if (two.size() == 2 && two[0].distance < options.ratio * two[1].distance) expected.push_back(two[0]);
    ASSERT_GT(expected.size(), 60u) << bytes << " bytes";
    DescriptorMatcher matcher(options);
    matcher.setReference(reference);
    const std::vector<cv::DMatch> matches = matcher.match(query);
    EXPECT_TRUE(sameMatches(matches, expected)) << bytes << " bytes: " << matches.size() << " vs " << expected.size();
  }
}

TEST(DescriptorMatcher, ReturnsNoMatchesForEmptyInput) {
  const cv::Mat some = clusteredDescriptors(20, 2);
  for (const MatcherKind kind : {MatcherKind::BruteForce, MatcherKind::FlannLsh, MatcherKind::Lsh}) {
    DescriptorMatcher matcher(withKind(kind));
    EXPECT_TRUE(matcher.match(some).empty()) << "no reference set";
    matcher.setReference(cv::Mat());
    EXPECT_TRUE(matcher.match(some).empty());
    matcher.setReference(cv::Mat(0, 32, CV_8U));
    EXPECT_TRUE(matcher.match(some).empty());
    matcher.setReference(some);
    EXPECT_TRUE(matcher.match(cv::Mat()).empty());
    EXPECT_TRUE(matcher.match(cv::Mat(0, 32, CV_8U)).empty());
    // A single reference row has no second nearest for the ratio test.
    matcher.setReference(some.row(0));
    EXPECT_TRUE(matcher.match(some).empty());
  }
}

TEST(DescriptorMatcher, RefusesNonBinaryOrMismatchedDescriptors) {
  DescriptorMatcher matcher;
  EXPECT_THROW(matcher.setReference(cv::Mat(10, 32, CV_32F, cv::Scalar(0))), std::invalid_argument);
  matcher.setReference(clusteredDescriptors(10, 3));
  EXPECT_THROW(matcher.match(cv::Mat(10, 32, CV_32F, cv::Scalar(0))), std::invalid_argument);
  EXPECT_THROW(matcher.match(cv::Mat(10, 64, CV_8U, cv::Scalar(0))), std::invalid_argument);
  DescriptorMatcherOptions options;
  options.ratio = 0.0f;
  EXPECT_THROW(DescriptorMatcher{options}, std::invalid_argument);
}

TEST(DescriptorMatcher, ParsesMatcherNames) {
  EXPECT_EQ(frontend::parseMatcherKind("flann"), MatcherKind::FlannLsh);
  EXPECT_EQ(frontend::parseMatcherKind("brute-force"), MatcherKind::BruteForce);
  EXPECT_EQ(frontend::parseMatcherKind(frontend::matcherKindName(MatcherKind::BruteForce)), MatcherKind::BruteForce);
  EXPECT_THROW(frontend::parseMatcherKind("bf"), std::invalid_argument);
}

}  // namespace
