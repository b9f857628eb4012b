// The weighted correspondence rule: drop-in equivalence with PCL for k = 1,
// the argmax and tie rules, the reciprocal rule, weight sources, threads, and
// the warnings of the PCL setters it ignores.

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include <pcl/common/transforms.h>
#include <pcl/console/print.h>
#include <pcl/point_representation.h>
#include <pcl/point_types.h>
#include <pcl/registration/correspondence_estimation.h>
#include <pcl/registration/icp.h>
#include <pcl/search/kdtree.h>
#include "random_clouds.h"

#include "test_support.h"
#include "weighted_icp/io/map_format.h"
#include "weighted_icp/registration/landmark_point.h"
#include "weighted_icp/registration/rigid_motion.h"
#include "weighted_icp/registration/weighted_correspondence_estimation.h"

namespace {

using weighted_icp::LandmarkCloud;
using weighted_icp::LandmarkPoint;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;
using Weighted = weighted_icp::WeightedCorrespondenceEstimation<pcl::PointXYZ, pcl::PointXYZ>;
using Stock = pcl::registration::CorrespondenceEstimation<pcl::PointXYZ, pcl::PointXYZ>;

Cloud::Ptr cloudOf(std::initializer_list<std::array<float, 3>> points) {
  auto cloud = std::make_shared<Cloud>();
  for (const auto& p : points) cloud->push_back(pcl::PointXYZ(p[0], p[1], p[2]));
  return cloud;
}

/// Random points with exact duplicates, so that distance ties (FLANN's order) occur.
Cloud::Ptr cloudWithTies(std::size_t n, unsigned seed) { return weighted_icp::testing::randomCloud(n, seed, 1.0f, 20); }

Cloud::Ptr displaced(const Cloud& cloud, const weighted_icp::Displacement& d) {
  auto out = std::make_shared<Cloud>();
  pcl::transformPointCloud(cloud, *out, d.toIsometry().matrix().cast<float>());
  return out;
}

/// The real map's landmarks with >= 2 observations as xyz points.
Cloud::Ptr realMapCloud() {
  const auto map = weighted_icp::io::readLandmarkMap(weighted_icp::testing::realMapPath()).withMinObservations(2);
  auto cloud = std::make_shared<Cloud>();
  for (const auto& l : map.landmarks)
    cloud->push_back(pcl::PointXYZ(static_cast<float>(l.position.x()), static_cast<float>(l.position.y()),
                                   static_cast<float>(l.position.z())));
  return cloud;
}

void expectSameCorrespondences(const pcl::Correspondences& a, const pcl::Correspondences& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].index_query, b[i].index_query) << "at " << i;
    ASSERT_EQ(a[i].index_match, b[i].index_match) << "at " << i;
    ASSERT_EQ(a[i].distance, b[i].distance) << "at " << i;  // bit for bit
  }
}

pcl::Correspondences correspondencesOf(
    pcl::registration::CorrespondenceEstimationBase<pcl::PointXYZ, pcl::PointXYZ>& ce, const Cloud::Ptr& source,
    const Cloud::Ptr& target, double max_distance, bool reciprocal = false) {
  ce.setInputSource(source);
  ce.setInputTarget(target);
  pcl::Correspondences out;
  if (reciprocal)
    ce.determineReciprocalCorrespondences(out, max_distance);
  else
    ce.determineCorrespondences(out, max_distance);
  return out;
}

// --- Drop-in equivalence with PCL -----------------------------------------

void expectEquivalentToPcl(const Cloud::Ptr& source, const Cloud::Ptr& target) {
  for (const double max_distance : {std::numeric_limits<double>::max(), 0.05, 0.2}) {
    for (const bool reciprocal : {false, true}) {
      Stock stock;
      Weighted weighted(1);
      const auto expected = correspondencesOf(stock, source, target, max_distance, reciprocal);
      const auto actual = correspondencesOf(weighted, source, target, max_distance, reciprocal);
      ASSERT_FALSE(expected.empty());
      SCOPED_TRACE(testing::Message() << "max distance " << max_distance << (reciprocal ? ", reciprocal" : ""));
      expectSameCorrespondences(expected, actual);
    }
  }
}

TEST(WeightedCorrespondenceEstimation, KEqualsOneMatchesPclOnRandomCloudsWithDuplicates) {
  const auto target = cloudWithTies(3000, 1);
  expectEquivalentToPcl(displaced(*target, {0.03, -0.02, 0.01, 1, 2, 4}), target);
}

TEST(WeightedCorrespondenceEstimation, KEqualsOneMatchesPclOnTheRealMap) {
  WEIGHTED_ICP_REQUIRE_FILE(weighted_icp::testing::realMapPath());
  const auto target = realMapCloud();
  expectEquivalentToPcl(displaced(*target, {0.1, 0.05, -0.02, 2, -1, 10}), target);
}

TEST(WeightedCorrespondenceEstimation, UniformWeightsWithLargerKStillMatchPcl) {
  // All weights equal: the tie rule picks the nearest of the k, i.e. PCL's choice.
  const auto target = cloudWithTies(2000, 2);
  const auto source = displaced(*target, {0.02, 0.0, 0.01, 0, 0, 3});
  Stock stock;
  Weighted weighted(7);
  weighted.setTargetWeights(std::vector<double>(target->size(), 0.5));
  expectSameCorrespondences(correspondencesOf(stock, source, target, 1.0),
                            correspondencesOf(weighted, source, target, 1.0));
}

TEST(WeightedCorrespondenceEstimation, IcpWithKEqualsOneIsBitIdenticalToPclIcp) {
  WEIGHTED_ICP_REQUIRE_FILE(weighted_icp::testing::realMapPath());
  const auto target = realMapCloud();
  const auto source = displaced(*target, {0.15, -0.1, 0.05, 3, -2, 12});
  auto run = [&](const pcl::registration::CorrespondenceEstimationBase<pcl::PointXYZ, pcl::PointXYZ, double>::Ptr& ce) {
    pcl::IterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ, double> icp;
    if (ce) icp.setCorrespondenceEstimation(ce);
    icp.setMaximumIterations(60);
    icp.setInputSource(source);
    icp.setInputTarget(target);
    Cloud aligned;
    icp.align(aligned);
    return std::make_pair(Eigen::Matrix4d(icp.getFinalTransformation()), icp.getFitnessScore());
  };
  const auto [stock_t, stock_score] = run(nullptr);  // PCL's own CorrespondenceEstimation
  const auto [ours_t, ours_score] =
      run(std::make_shared<weighted_icp::WeightedCorrespondenceEstimation<pcl::PointXYZ, pcl::PointXYZ, double>>(1));
  for (int i = 0; i < 16; ++i) EXPECT_EQ(stock_t.data()[i], ours_t.data()[i]) << "entry " << i;
  EXPECT_EQ(stock_score, ours_score);
  // And it did something: the displacement was undone.
  EXPECT_LT(
      weighted_icp::rotationErrorDeg(Eigen::Isometry3d(ours_t),
                                     weighted_icp::Displacement{0.15, -0.1, 0.05, 3, -2, 12}.toIsometry().inverse()),
      0.01);
}

// --- The rule -----------------------------------------------------------------

TEST(WeightedCorrespondenceEstimation, ChoosesTheHeaviestOfTheKNearest) {
  const auto target = cloudOf({{1, 0, 0}, {2, 0, 0}, {3, 0, 0}, {4, 0, 0}});
  const auto source = cloudOf({{0, 0, 0}});
  Weighted ce(3);
  ce.setTargetWeights({1.0, 2.0, 3.0, 100.0});  // the heaviest overall is the 4th nearest
  const auto c = correspondencesOf(ce, source, target, 10.0);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].index_query, 0);
  EXPECT_EQ(c[0].index_match, 2);
  EXPECT_FLOAT_EQ(c[0].distance, 9.0f);  // squared, as PCL
  ce.setNumberOfNeighbors(4);
  EXPECT_EQ(correspondencesOf(ce, source, target, 10.0)[0].index_match, 3);
  ce.setNumberOfNeighbors(1);
  EXPECT_EQ(correspondencesOf(ce, source, target, 10.0)[0].index_match, 0);
}

TEST(WeightedCorrespondenceEstimation, EqualWeightsGoToTheNearest) {
  const auto target = cloudOf({{3, 0, 0}, {1, 0, 0}, {2, 0, 0}});
  const auto source = cloudOf({{0, 0, 0}});
  Weighted ce(3);
  ce.setTargetWeights({5.0, 1.0, 5.0});
  EXPECT_EQ(correspondencesOf(ce, source, target, 10.0)[0].index_match, 2);  // at 2, not at 3
}

TEST(WeightedCorrespondenceEstimation, CandidatesBeyondTheMaximumDistanceAreNotChosen) {
  const auto target = cloudOf({{1, 0, 0}, {2, 0, 0}, {3, 0, 0}});
  const auto source = cloudOf({{0, 0, 0}, {10, 0, 0}});
  Weighted ce(3);
  ce.setTargetWeights({1.0, 2.0, 3.0});
  const auto c = correspondencesOf(ce, source, target, 2.5);
  ASSERT_EQ(c.size(), 1u);  // the far source point has no partner within 2.5
  EXPECT_EQ(c[0].index_query, 0);
  EXPECT_EQ(c[0].index_match, 1);  // the heavier point at 3 is out of range
}

TEST(WeightedCorrespondenceEstimation, NonFinitePointsAreNeverMatched) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const auto target = cloudOf({{nan, 0, 0}, {1, 0, 0}});
  const auto source = cloudOf({{0, 0, 0}, {0, nan, 0}, {1, 0, 0}});
  Weighted ce(2);
  const auto c = correspondencesOf(ce, source, target, 10.0);
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c[0].index_query, 0);
  EXPECT_EQ(c[0].index_match, 1);
  EXPECT_EQ(c[1].index_query, 2);
  EXPECT_EQ(c[1].index_match, 1);
}

TEST(WeightedCorrespondenceEstimation, RespectsSourceAndTargetIndices) {
  const auto target = cloudOf({{1, 0, 0}, {0.5, 0, 0}, {5, 0, 0}});
  const auto source = cloudOf({{0, 0, 0}, {5, 0, 0}});
  Weighted ce(1);
  ce.setInputSource(source);
  ce.setInputTarget(target);
  ce.setIndicesSource(std::make_shared<pcl::Indices>(pcl::Indices{1}));
  ce.setIndicesTarget(std::make_shared<pcl::Indices>(pcl::Indices{0, 2}));
  pcl::Correspondences c;
  ce.determineCorrespondences(c);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].index_query, 1);
  EXPECT_EQ(c[0].index_match, 2);  // cloud index, not position in the indices
}

// --- The reciprocal rule ---------------------------------------------------------

TEST(WeightedCorrespondenceEstimation, ReciprocalKeepsOnlyPairsChosenFromBothSides) {
  // Source s0 at 0 and s1 at 0.9; target t0 at 1 (heavy), t1 at -1 (light).
  const auto target = cloudOf({{1, 0, 0}, {-1, 0, 0}});
  const auto source = cloudOf({{0, 0, 0}, {0.9, 0, 0}});
  Weighted ce(2);
  ce.setTargetWeights({10.0, 1.0});
  // Forward both choose t0. Backward from t0 with uniform source weights the
  // nearest source, s1, is chosen: only (s1, t0) is reciprocal.
  auto c = correspondencesOf(ce, source, target, 10.0, true);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].index_query, 1);
  EXPECT_EQ(c[0].index_match, 0);
  // Make s0 the heavier source: now t0's choice is s0, and (s0, t0) is kept.
  ce.setSourceWeights({5.0, 1.0});
  c = correspondencesOf(ce, source, target, 10.0, true);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].index_query, 0);
  EXPECT_EQ(c[0].index_match, 0);
  // The non-reciprocal rule keeps both.
  EXPECT_EQ(correspondencesOf(ce, source, target, 10.0).size(), 2u);
}

// --- Where weights come from -----------------------------------------------------

LandmarkCloud::Ptr landmarkCloud(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> coordinate(-1.0f, 1.0f);
  std::uniform_real_distribution<double> weight(0.0, 1.0);
  auto cloud = std::make_shared<LandmarkCloud>();
  for (std::size_t i = 0; i < n; ++i) {
    LandmarkPoint p{};
    p.x = coordinate(rng);
    p.y = coordinate(rng);
    p.z = coordinate(rng);
    p.weight = weight(rng);
    cloud->push_back(p);
  }
  return cloud;
}

TEST(WeightedCorrespondenceEstimation, WeightsFromTheFieldEqualWeightsFromAVector) {
  using LandmarkCe = weighted_icp::WeightedCorrespondenceEstimation<LandmarkPoint, LandmarkPoint>;
  const auto target = landmarkCloud(1500, 3);
  const auto source = landmarkCloud(1000, 4);
  std::vector<double> weights;
  for (const auto& p : *target) weights.push_back(p.weight);
  auto run = [&](LandmarkCe& ce) {
    ce.setInputSource(source);
    ce.setInputTarget(target);
    pcl::Correspondences c;
    ce.determineCorrespondences(c, 0.3);
    return c;
  };
  LandmarkCe from_field(5), from_vector(5), reversed(5);
  from_vector.setTargetWeights(weights);
  for (auto& w : weights) w = 1.0 - w;
  reversed.setTargetWeights(weights);  // a vector takes precedence over the field
  const auto by_field = run(from_field);
  expectSameCorrespondences(by_field, run(from_vector));
  const auto by_reversed = run(reversed);
  ASSERT_EQ(by_field.size(), by_reversed.size());
  std::size_t differ = 0;
  for (std::size_t i = 0; i < by_field.size(); ++i) differ += by_field[i].index_match != by_reversed[i].index_match;
  EXPECT_GT(differ, by_field.size() / 4);
}

TEST(WeightedCorrespondenceEstimation, ANamedFieldIsRead) {
  using IntensityCe = weighted_icp::WeightedCorrespondenceEstimation<pcl::PointXYZI, pcl::PointXYZI>;
  auto target = std::make_shared<pcl::PointCloud<pcl::PointXYZI>>();
  for (const float x : {1.0f, 2.0f}) {
    pcl::PointXYZI p;
    p.x = x;
    p.y = p.z = 0;
    p.intensity = x;  // the farther point is brighter
    target->push_back(p);
  }
  auto source = std::make_shared<pcl::PointCloud<pcl::PointXYZI>>();
  source->push_back(pcl::PointXYZI(0.0f));
  IntensityCe ce(2);
  ce.setInputSource(source);
  ce.setInputTarget(target);
  pcl::Correspondences c;
  ce.determineCorrespondences(c);
  EXPECT_EQ(c.at(0).index_match, 0);  // PointXYZI has no "weight": uniform, nearest
  ce.setTargetWeightField("intensity");
  ce.determineCorrespondences(c);
  EXPECT_EQ(c.at(0).index_match, 1);
}

TEST(WeightedCorrespondenceEstimation, BadWeightsAreRefusedClearly) {
  const auto target = cloudOf({{1, 0, 0}, {2, 0, 0}});
  const auto source = cloudOf({{0, 0, 0}});
  Weighted ce(2);
  EXPECT_THROW(ce.setTargetWeights({1.0, std::nan("")}), std::invalid_argument);
  EXPECT_THROW(ce.setTargetWeights({1.0, -2.0}), std::invalid_argument);
  EXPECT_THROW(ce.setSourceWeights({std::numeric_limits<double>::infinity()}), std::invalid_argument);
  EXPECT_THROW(ce.setNumberOfNeighbors(0), std::invalid_argument);
  try {
    ce.setTargetWeights({1.0, 2.0, -1.0});
    FAIL() << "a negative weight was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("weight 2"), std::string::npos) << e.what();
  }
  // A size mismatch is found when the target is known: no correspondences.
  ce.setTargetWeights({1.0, 2.0, 3.0});
  EXPECT_TRUE(correspondencesOf(ce, source, target, 10.0).empty());
  ce.setTargetWeights({1.0, 2.0});
  EXPECT_EQ(correspondencesOf(ce, source, target, 10.0).size(), 1u);
  // A field named explicitly must exist.
  ce.setTargetWeights({});
  ce.setTargetWeightField("no_such_field");
  EXPECT_TRUE(correspondencesOf(ce, source, target, 10.0).empty());
}

TEST(WeightedCorrespondenceEstimation, NoTargetOrAnAllNanTargetGivesNoCorrespondences) {
  Weighted ce(3);
  ce.setInputSource(cloudOf({{0, 0, 0}}));
  pcl::Correspondences c{pcl::Correspondence(0, 0, 1.0f)};
  ce.determineCorrespondences(c);
  EXPECT_TRUE(c.empty());
  const float nan = std::numeric_limits<float>::quiet_NaN();
  ce.setInputTarget(cloudOf({{nan, nan, nan}}));
  ce.determineCorrespondences(c);
  EXPECT_TRUE(c.empty());
}

// --- Threads, index reuse, clone ---------------------------------------------------

TEST(WeightedCorrespondenceEstimation, ResultsDoNotDependOnTheNumberOfThreads) {
  const auto target = cloudWithTies(20000, 5);
  const auto source = displaced(*cloudWithTies(15000, 6), {0.01, 0.02, 0.0, 0, 0, 2});
  std::vector<double> weights(target->size());
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> count(1, 6);  // many ties, as observation counts
  for (auto& w : weights) w = count(rng);
  pcl::Correspondences reference[2];
  for (const unsigned threads : {1u, 2u, 3u, 8u}) {
    for (const bool reciprocal : {false, true}) {
      Weighted ce(5);
      ce.setNumberOfThreads(threads);
      ce.setTargetWeights(weights);
      const auto c = correspondencesOf(ce, source, target, 0.1, reciprocal);
      if (threads == 1) reference[reciprocal] = c;
      SCOPED_TRACE(testing::Message() << threads << " threads" << (reciprocal ? ", reciprocal" : ""));
      expectSameCorrespondences(reference[reciprocal], c);
    }
  }
  EXPECT_GT(reference[0].size(), 1000u);
  EXPECT_GT(reference[1].size(), 100u);
  EXPECT_LT(reference[1].size(), reference[0].size());
}

TEST(NearestNeighborIndex, ReSettingAnUnchangedCloudDoesNotRebuild) {
  const auto cloud = cloudWithTies(500, 8);
  weighted_icp::NearestNeighborIndex index;
  EXPECT_TRUE(index.build(*cloud));
  EXPECT_FALSE(index.build(*cloud));
  (*cloud)[10].x += 0.5f;
  EXPECT_TRUE(index.build(*cloud));
  weighted_icp::NearestNeighborIndex::Scratch scratch(3);
  const float query[3] = {(*cloud)[10].x, (*cloud)[10].y, (*cloud)[10].z};
  ASSERT_EQ(index.knn(query, scratch), 3u);
  EXPECT_EQ(scratch.indices()[0], 10);  // the rebuilt tree sees the moved point
  EXPECT_EQ(scratch.squaredDistances()[0], 0.0f);
}

// --- PCL setters it does not honour ----------------------------------------

/// Calls `setters` and returns what they printed to stderr, with PCL's warnings switched on.
template <typename Setters>
std::string stderrOf(Setters setters) {
  const auto previous = pcl::console::getVerbosityLevel();
  pcl::console::setVerbosityLevel(pcl::console::L_WARN);
  ::testing::internal::CaptureStderr();
  setters();
  const std::string printed = ::testing::internal::GetCapturedStderr();
  pcl::console::setVerbosityLevel(previous);
  return printed;
}

TEST(WeightedCorrespondenceEstimation, IgnoredPclSettersWarnAndChangeNothing) {
  const auto source = cloudWithTies(300, 11);
  const auto target = displaced(*source, {0.03, -0.02, 0.01, 1, 2, 4});
  // x stretched 100 times: PCL's own class, which honours it, then pairs points differently.
  auto stretched = std::make_shared<pcl::DefaultPointRepresentation<pcl::PointXYZ>>();
  const float rescale[3] = {100.0f, 1.0f, 1.0f};
  stretched->setRescaleValues(rescale);
  // A source tree over the target cloud, never rebuilt: wrong for the reciprocal search if it were used.
  auto wrong_tree = std::make_shared<pcl::search::KdTree<pcl::PointXYZ>>();
  wrong_tree->setInputCloud(target);

  Stock stock, stock_stretched;
  stock_stretched.setPointRepresentation(stretched);
  const auto stock_pairs = correspondencesOf(stock, source, target, 0.2);
  ASSERT_FALSE(stock_pairs.empty());
  const auto stretched_pairs = correspondencesOf(stock_stretched, source, target, 0.2);
  bool representation_matters = stock_pairs.size() != stretched_pairs.size();
  for (std::size_t i = 0; !representation_matters && i < stock_pairs.size(); ++i)
    representation_matters = stock_pairs[i].index_match != stretched_pairs[i].index_match;
  ASSERT_TRUE(representation_matters) << "the stretched representation should change PCL's pairs";

  Weighted plain(3), configured(3);
  const std::string warnings = stderrOf([&] {
    configured.setPointRepresentation(stretched);
    configured.setSearchMethodSource(wrong_tree, true);
  });
  EXPECT_NE(warnings.find("[pcl::registration::WeightedCorrespondenceEstimation::setPointRepresentation] "
                          "This class does not use a point representation"),
            std::string::npos)
      << warnings;
  EXPECT_NE(warnings.find("[pcl::registration::WeightedCorrespondenceEstimation::setSearchMethodSource] "
                          "This class does not use a source search method"),
            std::string::npos)
      << warnings;
  EXPECT_EQ(configured.getSearchMethodSource(), wrong_tree);  // stored, as the base class does
  for (const bool reciprocal : {false, true}) {
    SCOPED_TRACE(reciprocal ? "reciprocal" : "plain");
    expectSameCorrespondences(correspondencesOf(plain, source, target, 0.2, reciprocal),
                              correspondencesOf(configured, source, target, 0.2, reciprocal));
  }
}

TEST(WeightedCorrespondenceEstimation, IcpPassingItsTreesThroughTheBaseDoesNotWarn) {
  const auto target = cloudWithTies(200, 12);
  const auto source = displaced(*target, {0.02, 0.01, 0.0, 0, 0, 2});
  pcl::IterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ> icp;
  icp.setCorrespondenceEstimation(std::make_shared<Weighted>(1));
  icp.setInputSource(source);
  icp.setInputTarget(target);
  icp.setMaximumIterations(5);
  Cloud aligned;
  const std::string printed = stderrOf([&] { icp.align(aligned); });
  EXPECT_EQ(printed.find("setSearchMethodSource"), std::string::npos) << printed;
  EXPECT_EQ(aligned.size(), source->size());
}

TEST(WeightedCorrespondenceEstimation, CloneKeepsSettingsAndWorksIndependently) {
  const auto target = cloudOf({{1, 0, 0}, {2, 0, 0}, {3, 0, 0}});
  const auto source = cloudOf({{0, 0, 0}});
  auto original = std::make_shared<Weighted>(2);
  original->setTargetWeights({1.0, 4.0, 9.0});
  original->setNumberOfThreads(1);
  original->setInputSource(source);
  original->setInputTarget(target);
  const auto copy = std::dynamic_pointer_cast<Weighted>(original->clone());
  ASSERT_TRUE(copy);
  EXPECT_EQ(copy->getNumberOfNeighbors(), 2u);
  EXPECT_EQ(copy->getTargetWeights(), original->getTargetWeights());
  EXPECT_EQ(copy->getNumberOfThreads(), 1u);
  original->setNumberOfNeighbors(3);
  pcl::Correspondences a, b;
  original->determineCorrespondences(a);
  copy->determineCorrespondences(b);
  EXPECT_EQ(a.at(0).index_match, 2);
  EXPECT_EQ(b.at(0).index_match, 1);
}

}  // namespace
