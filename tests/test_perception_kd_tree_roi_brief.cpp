// The issue #11 matching pieces: the binary KD-tree (exact with enough
// backtracking, bounded otherwise, deterministic), matching in regions of
// interest, and the modified BRIEF descriptor (Eq. 7).

#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core/hal/hal.hpp>
#include <opencv2/imgproc.hpp>

#include "weighted_icp/frontend/perception/binary_kd_tree.h"
#include "weighted_icp/frontend/perception/descriptor_matcher.h"
#include "weighted_icp/frontend/perception/modified_brief.h"
#include "weighted_icp/frontend/perception/roi_matcher.h"

namespace {

using namespace weighted_icp::frontend;

cv::Mat randomDescriptors(int rows, unsigned seed) {
  cv::Mat d(rows, 32, CV_8UC1);
  std::mt19937 random(seed);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < 32; ++c) d.at<std::uint8_t>(r, c) = static_cast<std::uint8_t>(random() & 0xff);
  return d;
}

/// `row` with `bits` of its bits flipped (a near copy, as a feature seen again).
cv::Mat flipped(const cv::Mat& row, int bits, unsigned seed) {
  cv::Mat copy = row.clone();
  std::mt19937 random(seed);
  for (int i = 0; i < bits; ++i) {
    const int b = static_cast<int>(random() % 256);
    copy.at<std::uint8_t>(0, b / 8) ^= static_cast<std::uint8_t>(1u << (b % 8));
  }
  return copy;
}

int bruteForceBest(const cv::Mat& reference, const cv::Mat& query, int& distance) {
  int best = -1;
  distance = 1 << 30;
  for (int r = 0; r < reference.rows; ++r) {
    const int d = cv::hal::normHamming(query.ptr<std::uint8_t>(0), reference.ptr<std::uint8_t>(r), 32);
    if (d < distance) {
      distance = d;
      best = r;
    }
  }
  return best;
}

TEST(BinaryKdTree, UnboundedSearchIsExact) {
  const cv::Mat reference = randomDescriptors(400, 1);
  BinaryKdTree tree({8, 1 << 20});
  tree.build(reference);
  for (int q = 0; q < 40; ++q) {
    const cv::Mat query = flipped(reference.row(q * 7), 20 + q, 100 + q);
    int exact_distance = 0;
    bruteForceBest(reference, query, exact_distance);
    const TwoNearest found = tree.nearestTwo(query.ptr<std::uint8_t>(0));
    EXPECT_EQ(found.best_distance, exact_distance) << "query " << q;
    EXPECT_GE(found.second_distance, found.best_distance);
  }
}

TEST(BinaryKdTree, BoundedSearchFindsNearCopiesAndRepeats) {
  const cv::Mat reference = randomDescriptors(1500, 2);
  BinaryKdTree tree;  // default bound
  tree.build(reference);
  int found_source = 0;
  for (int q = 0; q < 100; ++q) {
    const cv::Mat query = flipped(reference.row(q * 13), 10, 300 + q);
    const TwoNearest first = tree.nearestTwo(query.ptr<std::uint8_t>(0));
    const TwoNearest again = tree.nearestTwo(query.ptr<std::uint8_t>(0));
    EXPECT_EQ(first.best, again.best);
    EXPECT_EQ(first.second, again.second);
    found_source += first.best == q * 13;
  }
  // 10 flipped bits of 256: the source row is the nearest, and the tree must find most of them.
  EXPECT_GE(found_source, 80);
}

TEST(BinaryKdTree, RefusesBadOptionsAndTypes) {
  EXPECT_THROW(BinaryKdTree({0, 4}), std::invalid_argument);
  EXPECT_THROW(BinaryKdTree({4, -1}), std::invalid_argument);
  BinaryKdTree tree;
  EXPECT_THROW(tree.build(cv::Mat(3, 8, CV_32F, cv::Scalar(0))), std::invalid_argument);
  tree.build(cv::Mat());
  EXPECT_EQ(tree.nearestTwo(randomDescriptors(1, 3).ptr<std::uint8_t>(0)).best, -1);
}

TEST(DescriptorMatcherKdTree, AgreesWithBruteForceOnNearCopies) {
  const cv::Mat reference = randomDescriptors(600, 4);
  cv::Mat query;
  for (int q = 0; q < 60; ++q) query.push_back(flipped(reference.row(q * 9), 12, 500 + q));
  DescriptorMatcherOptions options;
  options.kind = MatcherKind::KdTree;
  DescriptorMatcher kd(options);
  kd.setReference(reference);
  options.kind = MatcherKind::BruteForce;
  DescriptorMatcher exact(options);
  exact.setReference(reference);
  const auto kd_matches = kd.match(query), exact_matches = exact.match(query);
  EXPECT_GE(kd_matches.size() + 3, exact_matches.size());
  for (const cv::DMatch& m : kd_matches) EXPECT_EQ(m.trainIdx, m.queryIdx * 9);
  EXPECT_EQ(parseMatcherKind("kd-tree"), MatcherKind::KdTree);
  EXPECT_THROW(parseMatcherKind("kdtree"), std::invalid_argument);
}

TEST(RoiMatcher, MatchesOnlyWithinTheRadiusOfThePrediction) {
  const cv::Mat reference = randomDescriptors(3, 5);
  // Query 0 is reference 0's descriptor at its predicted pixel; query 1 is
  // reference 1's descriptor 60 px from its prediction: outside a 40 px region.
  const cv::Mat query = reference.rowRange(0, 2).clone();
  const std::vector<Eigen::Vector2d> query_pixels{{100, 100}, {300, 100}};
  const std::vector<Eigen::Vector2d> predicted{{102, 101}, {240, 100}, {500, 400}};
  RoiMatchOptions options;
  const auto matches = matchInRegionsOfInterest(query, query_pixels, reference, predicted, options);
  ASSERT_EQ(matches.size(), 1u);
  EXPECT_EQ(matches[0].queryIdx, 0);
  EXPECT_EQ(matches[0].trainIdx, 0);
  options.radius_px = 80.0;
  EXPECT_EQ(matchInRegionsOfInterest(query, query_pixels, reference, predicted, options).size(), 2u);
}

TEST(RoiMatcher, APredictionFarOutsideTheImageIsIgnoredNotAnError) {
  // A map point almost in the camera's plane projects millions of pixels away. It cannot be within the radius of any
  // feature: it used to make the grid over the predictions too large and the run stop with an error.
  const cv::Mat reference = randomDescriptors(4, 7);
  const cv::Mat query = reference.rowRange(0, 2).clone();  // rows 0 and 1, seen near their predictions
  const std::vector<Eigen::Vector2d> query_pixels{{100, 100}, {600, 400}};
  std::vector<Eigen::Vector2d> predicted{{102, 101}, {598, 403}, {320, 240}, {320, 240}};
  RoiMatchOptions options;
  const auto near_only = matchInRegionsOfInterest(query, query_pixels, reference, predicted, options);
  for (const Eigen::Vector2d& far : {Eigen::Vector2d(3e9, -2e9), Eigen::Vector2d(-1e12, 5e11)}) {
    predicted[3] = far;
    std::vector<cv::DMatch> matches;
    ASSERT_NO_THROW(matches = matchInRegionsOfInterest(query, query_pixels, reference, predicted, options));
    ASSERT_EQ(matches.size(), near_only.size());
    for (std::size_t i = 0; i < matches.size(); ++i) {
      EXPECT_EQ(matches[i].queryIdx, near_only[i].queryIdx);
      EXPECT_EQ(matches[i].trainIdx, near_only[i].trainIdx);
    }
  }
  EXPECT_EQ(near_only.size(), 2u);
}

TEST(RoiMatcher, RefusesMismatchedInputsAndBadOptions) {
  const cv::Mat reference = randomDescriptors(2, 6);
  const std::vector<Eigen::Vector2d> two{{1, 1}, {2, 2}}, one{{1, 1}};
  RoiMatchOptions options;
  EXPECT_THROW(matchInRegionsOfInterest(reference, one, reference, two, options), std::invalid_argument);
  EXPECT_THROW(matchInRegionsOfInterest(reference, two, reference, one, options), std::invalid_argument);
  options.radius_px = 0.0;
  EXPECT_THROW(matchInRegionsOfInterest(reference, two, reference, two, options), std::invalid_argument);
  EXPECT_EQ(parseMatchRegion("homography"), MatchRegion::Homography);
  EXPECT_THROW(parseMatchRegion("roi"), std::invalid_argument);
}

TEST(ModifiedBrief, AveragesFollowEquationSeven) {
  cv::Mat gray(5, 5, CV_8UC1);
  for (int i = 0; i < 25; ++i) gray.at<std::uint8_t>(i / 5, i % 5) = static_cast<std::uint8_t>(i * i % 251);
  const cv::Mat averaged = averageNeighbours(gray);
  const auto p = [&](int r, int c) { return static_cast<double>(gray.at<std::uint8_t>(r, c)); };
  const double p1 = (p(1, 1) + p(1, 2) + p(1, 3)) / 3, p2 = (p(2, 1) + p(2, 3)) / 2,
               p3 = (p(3, 1) + p(3, 2) + p(3, 3)) / 3;
  EXPECT_NEAR(averaged.at<float>(2, 2), (p1 + p2 + p3) / 3, 1e-3);
}

TEST(ModifiedBrief, DescribesDeterministicallyAndFollowsRotation) {
  cv::Mat gray(200, 200, CV_8UC1);
  cv::randu(gray, 0, 255);
  cv::GaussianBlur(gray, gray, cv::Size(5, 5), 1.5);
  std::vector<cv::KeyPoint> keypoints{cv::KeyPoint(100, 100, 31, 0), cv::KeyPoint(5, 5, 31, 0)};
  cv::Mat first, second;
  auto again = keypoints;
  computeModifiedBrief(gray, keypoints, first);
  computeModifiedBrief(gray, again, second);
  ASSERT_EQ(keypoints.size(), 1u) << "the keypoint at the border is dropped";
  EXPECT_EQ(first.cols, 32);
  EXPECT_EQ(cv::norm(first, second, cv::NORM_HAMMING), 0.0);
  // The image turned by 90 degrees about the keypoint, with the angle turned too: nearly the same bits.
  cv::Mat turned;
  cv::rotate(gray, turned, cv::ROTATE_90_COUNTERCLOCKWISE);
  std::vector<cv::KeyPoint> turned_keypoints{cv::KeyPoint(100, 99, 31, 270)};
  cv::Mat turned_descriptor;
  computeModifiedBrief(turned, turned_keypoints, turned_descriptor);
  ASSERT_EQ(turned_descriptor.rows, 1);
  EXPECT_LT(cv::norm(first, turned_descriptor, cv::NORM_HAMMING), 40.0);
  EXPECT_THROW(parseDescriptorKind("brief"), std::invalid_argument);
}

}  // namespace
