// Pose-graph optimisation: a drifted loop is pulled back to truth, a wrong loop edge is refused, bad edges throw.
#include <limits>
#include <tuple>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "pose_graph_fixtures.h"
#include "weighted_icp/mapping/pose_graph.h"

namespace weighted_icp::testing {
namespace {

using mapping::PoseGraph;
using mapping::PoseGraphEdgeKind;

TEST(PoseGraph, ClosingTheLoopPullsTheDriftedChainBackToTruth) {
  const DriftedLoop loop = makeDriftedLoop(60, 3.0, 0.1, 0.005);
  const double drifted_error = rmsPositionError(loop, loop.drifted);
  ASSERT_GT(drifted_error, 0.1) << "the fixture must drift for the test to mean anything";

  PoseGraph graph = makeOdometryGraph(loop);
  graph.addEdge(trueLoopEdge(loop, 0, 59));
  const auto summary = graph.optimize();
  ASSERT_TRUE(summary.ok) << summary.message;
  EXPECT_EQ(summary.loops_used, 1u);
  EXPECT_EQ(summary.loops_rejected, 0u);
  const double corrected_error = rmsPositionError(loop, posesOf(graph));
  EXPECT_LT(corrected_error, drifted_error / 3) << "drifted " << drifted_error << " m";
  // The fixed first keyframe stays where it was.
  EXPECT_TRUE(graph.poses().at(0).isApprox(loop.drifted[0], 1e-12));
}

TEST(PoseGraph, OneWrongLoopAmongGoodOnesIsRefusedAndTheResultStaysNearTruth) {
  const DriftedLoop loop = makeDriftedLoop(60, 3.0, 0.1, 0.005);
  PoseGraph graph = makeOdometryGraph(loop);
  graph.addEdge(trueLoopEdge(loop, 0, 59));
  // Perceptual aliasing: keyframes 10 and 40 (opposite sides of the circle) "recognised" as 0.8 m and 30 degrees
  // from where they really are to each other.
  Eigen::Isometry3d wrong = Eigen::Isometry3d::Identity();
  wrong.translation() = Eigen::Vector3d(0.8, 0.0, 0.3);
  wrong.linear() = Eigen::AngleAxisd(30 * M_PI / 180, Eigen::Vector3d::UnitY()).toRotationMatrix();
  graph.addEdge(trueLoopEdge(loop, 10, 40, wrong));
  graph.addEdge(trueLoopEdge(loop, 2, 57));

  const auto summary = graph.optimize();
  ASSERT_TRUE(summary.ok) << summary.message;
  EXPECT_EQ(summary.loops_rejected, 1u);
  EXPECT_EQ(summary.loops_used, 2u);
  ASSERT_EQ(summary.edge_used.size(), graph.edges().size());
  EXPECT_FALSE(summary.edge_used[graph.edges().size() - 2]) << "the wrong edge must be the one refused";

  PoseGraph without_wrong = makeOdometryGraph(loop);
  without_wrong.addEdge(trueLoopEdge(loop, 0, 59));
  without_wrong.addEdge(trueLoopEdge(loop, 2, 57));
  ASSERT_TRUE(without_wrong.optimize().ok);
  const double reference_error = rmsPositionError(loop, posesOf(without_wrong));
  EXPECT_NEAR(rmsPositionError(loop, posesOf(graph)), reference_error, 1e-6);
  EXPECT_LT(reference_error, rmsPositionError(loop, loop.drifted) / 3);
}

TEST(PoseGraph, LoopsAdmittedBeforeAreTestedTogetherInOneSolve) {
  // A loop closer's graph at its fifth closure: four loops accepted earlier, one new. Re-testing each earlier loop
  // alone was one solve per loop at every closure (quadratic over a run); together they take one.
  const DriftedLoop loop = makeDriftedLoop(60, 3.0, 0.1, 0.005);
  const std::vector<std::pair<std::size_t, std::size_t>> ends = {{0, 59}, {2, 57}, {5, 55}, {1, 50}, {3, 58}};
  PoseGraph together = makeOdometryGraph(loop), alone = makeOdometryGraph(loop);
  for (std::size_t i = 0; i < ends.size(); ++i) {
    mapping::PoseGraphEdge edge = trueLoopEdge(loop, ends[i].first, ends[i].second);
    alone.addEdge(edge);
    edge.admitted_before = i + 1 < ends.size();
    together.addEdge(edge);
  }
  const auto summary = together.optimize();
  const auto reference = alone.optimize();
  ASSERT_TRUE(summary.ok && reference.ok);
  EXPECT_EQ(summary.solves, 3u);  // odometry, the four earlier loops, the new one
  EXPECT_EQ(reference.solves, 6u);
  EXPECT_EQ(summary.loops_used, 5u);
  EXPECT_EQ(summary.loops_rejected, 0u);
  // The same optimum, reached in fewer steps.
  const auto a = posesOf(together), b = posesOf(alone);
  for (std::size_t i = 0; i < a.size(); ++i)
    EXPECT_LT((a[i].translation() - b[i].translation()).norm(), 1e-4) << "keyframe " << i;
  EXPECT_LT(rmsPositionError(loop, a), rmsPositionError(loop, loop.drifted) / 3);
}

TEST(PoseGraph, AWrongLoopAmongThoseAdmittedBeforeIsStillRefused) {
  // If the earlier loops fail together, each is tested alone again, as a new loop is.
  const DriftedLoop loop = makeDriftedLoop(60, 3.0, 0.1, 0.005);
  PoseGraph graph = makeOdometryGraph(loop);
  Eigen::Isometry3d wrong = Eigen::Isometry3d::Identity();
  wrong.translation() = Eigen::Vector3d(0.8, 0.0, 0.3);
  for (const auto& [match, query, error] :
       {std::tuple<std::size_t, std::size_t, Eigen::Isometry3d>{0, 59, Eigen::Isometry3d::Identity()},
        {10, 40, wrong},
        {2, 57, Eigen::Isometry3d::Identity()}}) {
    mapping::PoseGraphEdge edge = trueLoopEdge(loop, match, query, error);
    edge.admitted_before = true;
    graph.addEdge(edge);
  }
  const auto summary = graph.optimize();
  ASSERT_TRUE(summary.ok) << summary.message;
  EXPECT_EQ(summary.solves, 5u);  // odometry, the three together (refused), each alone
  EXPECT_EQ(summary.loops_used, 2u);
  EXPECT_EQ(summary.loops_rejected, 1u);
  EXPECT_FALSE(summary.edge_used[graph.edges().size() - 2]) << "the wrong edge must be the one refused";
}

TEST(PoseGraph, ExtremeGatesTestLoopsAdmittedBeforeAsTheyTestOne) {
  // An infinite gate (or one so wide that its probability rounds to 1) admits every loop, a gate of 0 none; the
  // joint gate of the earlier loops follows, instead of failing to find a chi-square quantile.
  const DriftedLoop loop = makeDriftedLoop(40, 2.0, 0.05, 0.003);
  for (const double gate : {std::numeric_limits<double>::infinity(), 1e6, 0.0}) {
    PoseGraph graph = makeOdometryGraph(loop);
    for (const auto& [match, query] : {std::pair<std::size_t, std::size_t>{0, 39}, {1, 38}, {2, 37}}) {
      mapping::PoseGraphEdge edge = trueLoopEdge(loop, match, query);
      edge.admitted_before = true;
      graph.addEdge(edge);
    }
    mapping::PoseGraphOptions options;
    options.loop_chi2_gate = gate;
    mapping::PoseGraphSummary summary;
    ASSERT_NO_THROW(summary = graph.optimize(options)) << "gate " << gate;
    ASSERT_TRUE(summary.ok) << summary.message;
    EXPECT_EQ(summary.loops_used, gate > 0.0 ? 3u : 0u) << "gate " << gate;
  }
}

TEST(PoseGraph, AWrongLoopAloneIsRefusedAndTheOdometryKept) {
  const DriftedLoop loop = makeDriftedLoop(40, 2.0, 0.05, 0.003);
  PoseGraph graph = makeOdometryGraph(loop);
  Eigen::Isometry3d wrong = Eigen::Isometry3d::Identity();
  wrong.translation() = Eigen::Vector3d(1.5, 0.2, 0.0);
  graph.addEdge(trueLoopEdge(loop, 5, 30, wrong));
  const auto summary = graph.optimize();
  ASSERT_TRUE(summary.ok);
  EXPECT_EQ(summary.loops_rejected, 1u);
  const auto poses = posesOf(graph);
  for (std::size_t i = 0; i < poses.size(); ++i)
    EXPECT_TRUE(poses[i].isApprox(loop.drifted[i], 1e-6)) << "keyframe " << i << " moved without a loop";
}

TEST(PoseGraph, InvalidEdgesAreRefusedWithTheirEnds) {
  PoseGraph graph;
  graph.addNode(0, Eigen::Isometry3d::Identity(), true);
  graph.addNode(1, Eigen::Isometry3d::Identity());
  mapping::PoseGraphEdge edge;
  edge.from = 0;
  edge.to = 2;
  EXPECT_THROW(graph.addEdge(edge), std::invalid_argument);
  edge.to = 1;
  edge.information(0, 0) = -1.0;
  try {
    graph.addEdge(edge);
    FAIL() << "a negative information must be refused";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("0 -> 1"), std::string::npos) << error.what();
  }
  edge.information.setIdentity();
  edge.to_in_from.translation().x() = std::nan("");
  EXPECT_THROW(graph.addEdge(edge), std::invalid_argument);
  Eigen::Isometry3d bad = Eigen::Isometry3d::Identity();
  bad.translation().y() = std::numeric_limits<double>::infinity();
  EXPECT_THROW(graph.addNode(3, bad), std::invalid_argument);
}

TEST(PoseGraph, OdometryInformationFollowsTheDocumentedModel) {
  mapping::OdometryNoiseModel model;
  Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
  step.translation() = Eigen::Vector3d(0.2, 0.0, 0.0);
  const auto information = mapping::odometryInformation(step, model);
  const double sigma_t = model.translation_sigma_m + 0.2 * model.translation_sigma_per_m;
  EXPECT_NEAR(information(0, 0), 1.0 / (sigma_t * sigma_t), 1e-9);
  EXPECT_NEAR(information(3, 3), 1.0 / (model.rotation_sigma_rad * model.rotation_sigma_rad), 1e-6);
  const auto weak = mapping::odometryInformation(step, model, true);
  EXPECT_NEAR(weak(0, 0), information(0, 0) / model.segment_break_factor, 1e-9);
  // Farther steps are trusted less.
  step.translation() *= 3;
  EXPECT_LT(mapping::odometryInformation(step, model)(0, 0), information(0, 0));
}

}  // namespace
}  // namespace weighted_icp::testing
