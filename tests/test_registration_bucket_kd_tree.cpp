// BucketKdTree is exact: its k nearest and its radius sets equal a brute-force search's, in float, on random
// clouds with duplicates, on degenerate clouds, for k larger than the cloud and for an empty tree.

#include <algorithm>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "random_clouds.h"
#include "weighted_icp/registration/bucket_kd_tree.h"
#include "weighted_icp/registration/nearest_neighbor_index.h"

namespace {

using weighted_icp::BucketKdTree;
using weighted_icp::NearestNeighborIndex;
using Row = BucketKdTree::Row;

std::vector<float> packed(const pcl::PointCloud<pcl::PointXYZ>& cloud) {
  std::vector<float> xyz;
  for (const auto& p : cloud) xyz.insert(xyz.end(), {p.x, p.y, p.z});
  return xyz;
}

/// Every point's float squared distance to `query`, sorted.
std::vector<float> bruteDistances(const std::vector<float>& xyz, const float* query) {
  std::vector<float> d;
  for (std::size_t i = 0; i < xyz.size() / 3; ++i)
    d.push_back(NearestNeighborIndex::squaredDistance(query, &xyz[3 * i]));
  std::sort(d.begin(), d.end());
  return d;
}

/// The tree's `k` nearest must be `k` distinct rows whose distances are the brute force's first `k`, sorted,
/// each the row's true distance (rows among equal distances may differ).
void expectNearestExact(const BucketKdTree& tree, const std::vector<float>& xyz, const float* query, std::size_t k) {
  const std::vector<float> truth = bruteDistances(xyz, query);
  std::vector<Row> rows(k);
  std::vector<float> distances(k);
  const std::size_t found = tree.nearest(query, k, rows.data(), distances.data());
  ASSERT_EQ(found, std::min(k, truth.size()));
  std::vector<Row> distinct(rows.begin(), rows.begin() + found);
  std::sort(distinct.begin(), distinct.end());
  EXPECT_EQ(std::unique(distinct.begin(), distinct.end()), distinct.end()) << "a row returned twice";
  for (std::size_t i = 0; i < found; ++i) {
    EXPECT_EQ(distances[i], truth[i]) << "neighbour " << i << " of " << k;
    EXPECT_EQ(distances[i], NearestNeighborIndex::squaredDistance(query, &xyz[3 * rows[i]]));
  }
}

std::vector<float> queriesNear(const std::vector<float>& xyz, unsigned seed, float jitter, std::size_t count) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<std::size_t> pick(0, xyz.size() / 3 - 1);
  std::normal_distribution<float> noise(0.0f, jitter);
  std::vector<float> queries;
  for (std::size_t i = 0; i < count; ++i) {
    const std::size_t p = pick(rng);
    // Half exactly on a point (distance 0, duplicates tie), half displaced.
    for (int a = 0; a < 3; ++a) queries.push_back(xyz[3 * p + a] + (i % 2 ? noise(rng) : 0.0f));
  }
  return queries;
}

TEST(BucketKdTree, NearestMatchesBruteForceWithDuplicates) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const auto cloud = weighted_icp::testing::randomCloud(2000, seed, 1.0f, 5);  // 400 exact duplicates
    const std::vector<float> xyz = packed(*cloud);
    for (std::size_t leaf : {1u, 3u, 12u, 64u}) {
      BucketKdTree tree;
      tree.build(xyz.data(), xyz.size() / 3, leaf);
      ASSERT_EQ(tree.size(), cloud->size());
      const std::vector<float> queries = queriesNear(xyz, seed + 10, 0.05f, 200);
      for (std::size_t q = 0; q < queries.size() / 3; ++q)
        for (std::size_t k : {1u, 6u, 24u, 70u}) expectNearestExact(tree, xyz, &queries[3 * q], k);
    }
  }
}

TEST(BucketKdTree, QueriesFarOutsideTheCloud) {
  const auto cloud = weighted_icp::testing::randomCloud(500, 4, 1.0f, 0);
  const std::vector<float> xyz = packed(*cloud);
  BucketKdTree tree;
  tree.build(xyz.data(), xyz.size() / 3);
  const float far[][3] = {{100.0f, 0.0f, 0.0f}, {-50.0f, 80.0f, 3.0f}, {1e6f, -1e6f, 1e6f}};
  for (const auto& query : far) expectNearestExact(tree, xyz, query, 6);
}

TEST(BucketKdTree, KLargerThanTheCloudReturnsEveryPointSorted) {
  const auto cloud = weighted_icp::testing::randomCloud(7, 5, 1.0f, 2);  // 7 points and 3 duplicates
  const std::vector<float> xyz = packed(*cloud);
  BucketKdTree tree;
  tree.build(xyz.data(), xyz.size() / 3, 2);
  const float query[3] = {0.1f, -0.2f, 0.3f};
  expectNearestExact(tree, xyz, query, 50);
}

TEST(BucketKdTree, EveryPointTheSameAndOnAPlane) {
  // All points identical: the median split must still terminate, and every distance ties.
  std::vector<float> same;
  for (int i = 0; i < 300; ++i) same.insert(same.end(), {0.5f, 0.5f, 0.5f});
  BucketKdTree tree;
  tree.build(same.data(), same.size() / 3, 4);
  const float query[3] = {0.0f, 0.0f, 0.0f};
  expectNearestExact(tree, same, query, 24);
  // Points on a line in one axis: the other axes have no spread.
  std::vector<float> line;
  for (int i = 0; i < 300; ++i) line.insert(line.end(), {0.01f * static_cast<float>(i % 50), 1.0f, 2.0f});
  tree.build(line.data(), line.size() / 3, 4);
  const float on_line[3] = {0.235f, 1.0f, 2.0f};
  expectNearestExact(tree, line, on_line, 24);
}

TEST(BucketKdTree, EmptyTreeFindsNothing) {
  BucketKdTree tree;
  tree.build(nullptr, 0);
  EXPECT_EQ(tree.size(), 0u);
  const float query[3] = {0.0f, 0.0f, 0.0f};
  Row row = 7;
  float distance = -1.0f;
  EXPECT_EQ(tree.nearest(query, 3, &row, &distance), 0u);
  std::vector<Row> rows;
  EXPECT_TRUE(tree.within(query, 1.0f, 10, rows));
  EXPECT_TRUE(rows.empty());
}

TEST(BucketKdTree, WithinMatchesBruteForceAndStopsAtTheLimit) {
  const auto cloud = weighted_icp::testing::randomCloud(1500, 6, 1.0f, 4);
  const std::vector<float> xyz = packed(*cloud);
  BucketKdTree tree;
  tree.build(xyz.data(), xyz.size() / 3, 8);
  const std::vector<float> queries = queriesNear(xyz, 16, 0.1f, 100);
  for (std::size_t q = 0; q < queries.size() / 3; ++q) {
    const float* query = &queries[3 * q];
    const float radius_sq = 0.02f;
    std::vector<Row> truth;
    for (std::size_t i = 0; i < xyz.size() / 3; ++i)
      if (NearestNeighborIndex::squaredDistance(query, &xyz[3 * i]) <= radius_sq) truth.push_back(static_cast<Row>(i));
    std::vector<Row> rows;
    ASSERT_TRUE(tree.within(query, radius_sq, truth.size(), rows));
    std::sort(rows.begin(), rows.end());
    EXPECT_EQ(rows, truth);
    if (truth.size() >= 2) {
      std::vector<Row> part;
      EXPECT_FALSE(tree.within(query, radius_sq, truth.size() - 1, part));
    }
  }
}

}  // namespace
