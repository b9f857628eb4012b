// Inputs that used to crash, hang or pass as success (issue #10): coordinates
// the float index cannot hold, degenerate point sets, absurd k and thread
// counts. Each must end in an exception naming the problem or a result
// flagged degenerate, never a crash or a "converged".

#include <cfloat>
#include <random>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include <pcl/point_types.h>
#include "random_clouds.h"

#include "weighted_icp/registration/landmark_alignment.h"
#include "weighted_icp/registration/weighted_correspondence_estimation.h"

namespace {

using namespace weighted_icp;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;
using Weighted = WeightedCorrespondenceEstimation<pcl::PointXYZ, pcl::PointXYZ>;

Cloud::Ptr identicalCloud(std::size_t n, float coordinate) {
  auto cloud = std::make_shared<Cloud>();
  cloud->resize(n, pcl::PointXYZ(coordinate, coordinate, coordinate));
  return cloud;
}

/// Random points in a 10 m cube.
Cloud::Ptr cubeCloud(std::size_t n, unsigned seed) { return weighted_icp::testing::randomCloud(n, seed, 5.0f, 0); }

LandmarkCloud::Ptr landmarks(const Cloud& points) {
  auto cloud = std::make_shared<LandmarkCloud>();
  for (const auto& p : points) {
    LandmarkPoint l{};
    l.x = p.x;
    l.y = p.y;
    l.z = p.z;
    l.weight = 1.0;
    l.num_observations = 2;
    cloud->push_back(l);
  }
  return cloud;
}

/// The message of the std::invalid_argument `f` throws; fails the test when it throws nothing.
template <typename F>
std::string invalidArgumentMessage(F f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  ADD_FAILURE() << "no std::invalid_argument";
  return {};
}

pcl::Correspondences correspondences(Weighted& ce, const Cloud::Ptr& source, const Cloud::Ptr& target) {
  ce.setInputSource(source);
  ce.setInputTarget(target);
  pcl::Correspondences result;
  ce.determineCorrespondences(result);
  return result;
}

TEST(RegistrationRobustness, HugeIdenticalTargetIsRefusedNamingThePoint) {
  // 1.8e38 fits a float, but FLANN's split (min + max) / 2 overflows: this recursed until the stack broke.
  for (const float huge : {1.8e38f, FLT_MAX, -FLT_MAX}) {
    Weighted ce(5);
    const std::string message =
        invalidArgumentMessage([&] { correspondences(ce, cubeCloud(10, 1), identicalCloud(20, huge)); });
    EXPECT_NE(message.find("target point 0"), std::string::npos) << message;

    LandmarkAligner aligner;
    const std::string aligner_message =
        invalidArgumentMessage([&] { aligner.setTarget(landmarks(*identicalCloud(20, huge))); });
    EXPECT_NE(aligner_message.find("target point 0"), std::string::npos) << aligner_message;
  }
}

TEST(RegistrationRobustness, OneUnindexablePointAmongValidOnesIsNamed) {
  const auto target = cubeCloud(30, 2);
  (*target)[17].y = 2.5e38f;
  LandmarkAligner aligner;
  const std::string message = invalidArgumentMessage([&] { aligner.setTarget(landmarks(*target)); });
  EXPECT_NE(message.find("point 17"), std::string::npos) << message;
  // As a source it is refused the same way, not silently matched at infinite distances.
  LandmarkAligner valid;
  valid.setTarget(landmarks(*cubeCloud(30, 3)));
  EXPECT_NE(invalidArgumentMessage([&] { valid.align(landmarks(*target)); }).find("source point 17"),
            std::string::npos);
}

TEST(RegistrationRobustness, CoordinatesUpToTheLimitAreAccepted) {
  Weighted ce(2);
  const auto target = cubeCloud(30, 4);
  (*target)[3].x = static_cast<float>(NearestNeighborIndex::kMaxCoordinate);
  (*target)[4].z = -static_cast<float>(NearestNeighborIndex::kMaxCoordinate);
  EXPECT_NO_THROW(correspondences(ce, cubeCloud(10, 5), target));
}

TEST(RegistrationRobustness, IdenticalTargetsBuildWithoutUnboundedRecursion) {
  for (const std::size_t n : {std::size_t{20}, std::size_t{1000000}}) {
    SCOPED_TRACE(n);
    Weighted ce(5);
    const auto found = correspondences(ce, cubeCloud(600, 6), identicalCloud(n, 1.5f));
    ASSERT_EQ(found.size(), 600u);  // every source point finds one of the identical points
    for (const auto& c : found) EXPECT_LT(c.index_match, static_cast<int>(n));

    LandmarkAligner aligner;
    aligner.setTarget(landmarks(*identicalCloud(n, 1.5f)));
    const AlignmentResult result = aligner.align(landmarks(*cubeCloud(50, 7)));
    EXPECT_TRUE(result.degenerate);
    EXPECT_FALSE(result.converged);
    EXPECT_NE(result.reason.find("identical"), std::string::npos) << result.reason;
  }
}

AlignmentResult alignClouds(const Cloud& source, const Cloud& target, unsigned int k) {
  AlignmentSettings settings;
  settings.k = k;
  LandmarkAligner aligner(settings);
  aligner.setTarget(landmarks(target));
  return aligner.align(landmarks(source));
}

TEST(RegistrationRobustness, DegenerateProblemsAreReportedNotConverged) {
  const auto good = cubeCloud(50, 8);
  Cloud line;
  for (int i = 0; i < 40; ++i) line.push_back(pcl::PointXYZ(0.1f * i, 0.2f * i, -0.3f * i));
  Cloud two;
  two.push_back(pcl::PointXYZ(0, 0, 0));
  two.push_back(pcl::PointXYZ(1, 0, 0));
  Cloud four;  // a tetrahedron: fine in shape, but k = 5 covers all of it
  for (const auto& p : {pcl::PointXYZ(0, 0, 0), pcl::PointXYZ(1, 0, 0), pcl::PointXYZ(0, 1, 0), pcl::PointXYZ(0, 0, 1)})
    four.push_back(p);

  const struct {
    const Cloud& source;
    const Cloud& target;
    unsigned int k;
    const char* reason;
  } cases[] = {{*good, two, 1, "only 2 finite target points"},
               {*good, line, 1, "target points are collinear"},
               {line, *good, 1, "source points are collinear"},
               {*good, four, 5, "k = 5 is at least the 4 finite target points"},
               {*good, four, 4, "k = 4 is at least"}};
  for (const auto& c : cases) {
    SCOPED_TRACE(c.reason);
    const AlignmentResult result = alignClouds(c.source, c.target, c.k);
    EXPECT_TRUE(result.degenerate);
    EXPECT_FALSE(result.converged);
    EXPECT_EQ(result.iterations, 0);
    EXPECT_NE(result.reason.find(c.reason), std::string::npos) << result.reason;
  }
  const AlignmentResult fine = alignClouds(*good, four, 1);  // plain ICP onto 4 points is well posed
  EXPECT_FALSE(fine.degenerate) << fine.reason;
  EXPECT_TRUE(alignClouds(*good, *good, 5).converged);
}

TEST(RegistrationRobustness, AbsurdKCostsNoMoreThanKEqualToTheTarget) {
  // 1,000 source points: the search runs in its OpenMP region, where a bad_alloc used to abort.
  const auto source = cubeCloud(1000, 9);
  const auto target = cubeCloud(700, 10);
  Weighted whole(700);
  Weighted absurd(4294967295u);
  const auto expected = correspondences(whole, source, target);
  const auto found = correspondences(absurd, source, target);
  ASSERT_EQ(found.size(), expected.size());
  for (std::size_t i = 0; i < found.size(); ++i) EXPECT_EQ(found[i].index_match, expected[i].index_match);
}

TEST(RegistrationRobustness, AbsurdThreadCountsAreRefused) {
  Weighted ce(5);
  EXPECT_NO_THROW(ce.setNumberOfThreads(Weighted::kMaxThreads));
  EXPECT_THROW(ce.setNumberOfThreads(100000), std::invalid_argument);
  EXPECT_THROW(ce.setNumberOfThreads(4294967295u), std::invalid_argument);  // "-1" wrapped around
  EXPECT_EQ(ce.getNumberOfThreads(), Weighted::kMaxThreads);
  AlignmentSettings settings;
  settings.threads = 100000;
  EXPECT_NE(invalidArgumentMessage([&] { LandmarkAligner aligner(settings); }).find("100000"), std::string::npos);
}

}  // namespace
