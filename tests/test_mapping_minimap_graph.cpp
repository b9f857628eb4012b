// The mini-map graph: built from a SLAM map it merges back to that map, round-trips through its file, refuses
// corrupt files naming file and line, exports the merged map, and its anchors close a drifted loop.
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "pose_graph_fixtures.h"
#include "test_support.h"
#include "weighted_icp/frontend/slam/landmark_conversion.h"
#include "weighted_icp/io/cloud_io.h"
#include "weighted_icp/io/map_format.h"
#include "weighted_icp/mapping/minimap_graph.h"

namespace weighted_icp::testing {
namespace {

namespace fs = std::filesystem;

/// 12 keyframes along a line (a tracking loss after the 7th), each creating 4 points that the next keyframe sees too.
void fillLineMap(frontend::Map& map) {
  frontend::MapPointId previous_first = 0;
  for (std::size_t k = 0; k < 12; ++k) {
    frontend::Keyframe keyframe;
    keyframe.pose_wc.translation() = Eigen::Vector3d(0.1 * static_cast<double>(k), 0.0, 0.0);
    keyframe.pose_wc.linear() =
        Eigen::AngleAxisd(0.02 * static_cast<double>(k), Eigen::Vector3d::UnitY()).toRotationMatrix();
    keyframe.segment = k < 7 ? 0 : 1;
    const auto id = map.addKeyframe(keyframe);
    if (k > 0)
      for (frontend::MapPointId p = previous_first; p < previous_first + 4; ++p) {
        const auto point = *map.mapPoint(p);
        map.addObservation(p, {id, Eigen::Vector2d(300.0 + static_cast<double>(p), 200.0), 1.0}, point.position,
                           point.covariance, point.descriptor);
      }
    for (int j = 0; j < 4; ++j) {
      frontend::MapPoint point;
      point.position = keyframe.pose_wc * Eigen::Vector3d(0.3 * j - 0.5, 0.2 * j, 2.0 + 0.1 * j);
      point.covariance = Eigen::Vector3d(1e-4, 1e-4, 1e-3 * (j + 1)).asDiagonal();
      point.observations.push_back({id, Eigen::Vector2d(320.0 + j, 240.0 - j), 2.0});
      const auto point_id = map.addMapPoint(point);
      if (j == 0) previous_first = point_id;
    }
  }
}

TEST(MiniMapGraph, BuiltFromASlamMapItMergesBackToThatMap) {
  frontend::Map map;
  fillLineMap(map);
  const mapping::MiniMapGraph graph = mapping::MiniMapGraph::fromSlamMap(map, 5);
  // Segments of 7 and 5 keyframes cut every 5: 5 + 2 | 5.
  ASSERT_EQ(graph.nodes().size(), 3u);
  ASSERT_EQ(graph.edges().size(), 2u);
  EXPECT_EQ(graph.edges()[0].kind, mapping::MiniMapEdgeKind::Sequential);
  // The edge across the tracking loss is trusted far less.
  EXPECT_GT(graph.edges()[1].covariance(0, 0), 100 * graph.edges()[0].covariance(0, 0));
  // Anchored at the first keyframe: its pose in the anchor frame is the identity.
  EXPECT_TRUE(graph.nodes()[1].landmarks.frames.at(5).isApprox(Eigen::Isometry3d::Identity()));

  const LandmarkMap session = frontend::toLandmarkMap(map);
  const LandmarkMap merged = graph.mergedMap();
  ASSERT_EQ(merged.frames.size(), session.frames.size());
  ASSERT_EQ(merged.landmarks.size(), session.landmarks.size());
  for (std::size_t i = 0; i < session.landmarks.size(); ++i) {
    EXPECT_EQ(merged.landmarks[i].id, session.landmarks[i].id);
    EXPECT_LT((merged.landmarks[i].position - session.landmarks[i].position).norm(), 1e-12);
    EXPECT_EQ(merged.landmarks[i].observations.size(), session.landmarks[i].observations.size());
  }
}

mapping::MiniMapGraph graphWithLoop() {
  frontend::Map map;
  fillLineMap(map);
  mapping::MiniMapGraph graph = mapping::MiniMapGraph::fromSlamMap(map, 5);
  mapping::MiniMapEdge loop;
  loop.from = 0;
  loop.to = 2;
  loop.kind = mapping::MiniMapEdgeKind::Loop;
  loop.strategy = "covariance";
  loop.fitness = 2.5e-4;
  loop.to_in_from = graph.nodes()[0].anchor_wc.inverse() * graph.nodes()[2].anchor_wc;
  loop.covariance = Eigen::Matrix<double, 6, 6>::Identity() * 1e-4;
  loop.covariance(0, 1) = loop.covariance(1, 0) = 3e-5;
  graph.addEdge(loop);
  return graph;
}

TEST(MiniMapGraph, SaveLoadRoundTrip) {
  const mapping::MiniMapGraph graph = graphWithLoop();
  const fs::path file = scratchDir("round_trip") / "graph.txt";
  mapping::saveMiniMapGraph(graph, file.string());
  const mapping::MiniMapGraph loaded = mapping::loadMiniMapGraph(file.string());
  ASSERT_EQ(loaded.nodes().size(), graph.nodes().size());
  for (std::size_t n = 0; n < graph.nodes().size(); ++n) {
    const auto& a = graph.nodes()[n];
    const auto& b = loaded.nodes()[n];
    EXPECT_EQ(b.session, a.session);
    EXPECT_TRUE(b.anchor_wc.isApprox(a.anchor_wc, 1e-12));
    ASSERT_EQ(b.landmarks.frames.size(), a.landmarks.frames.size());
    ASSERT_EQ(b.landmarks.landmarks.size(), a.landmarks.landmarks.size());
    for (std::size_t i = 0; i < a.landmarks.landmarks.size(); ++i) {
      EXPECT_EQ(b.landmarks.landmarks[i].id, a.landmarks.landmarks[i].id);
      EXPECT_EQ(b.landmarks.landmarks[i].position, a.landmarks.landmarks[i].position);
      EXPECT_EQ(b.landmarks.landmarks[i].covariance, a.landmarks.landmarks[i].covariance);
      ASSERT_EQ(b.landmarks.landmarks[i].observations.size(), a.landmarks.landmarks[i].observations.size());
    }
  }
  ASSERT_EQ(loaded.edges().size(), graph.edges().size());
  for (std::size_t e = 0; e < graph.edges().size(); ++e) {
    const auto& a = graph.edges()[e];
    const auto& b = loaded.edges()[e];
    EXPECT_EQ(b.from, a.from);
    EXPECT_EQ(b.to, a.to);
    EXPECT_EQ(b.kind, a.kind);
    EXPECT_EQ(b.strategy, a.strategy);
    EXPECT_EQ(b.fitness, a.fitness);
    EXPECT_TRUE(b.to_in_from.isApprox(a.to_in_from, 1e-12));
    EXPECT_EQ(b.covariance, a.covariance);
  }
}

/// Saves the graph, replaces the first line starting with `prefix` by `text`, and expects the load to fail at it.
void expectCorruptLineRefused(const std::string& name, const std::string& prefix, const std::string& text,
                              const std::string& what) {
  const fs::path file = scratchDir(name) / "graph.txt";
  mapping::saveMiniMapGraph(graphWithLoop(), file.string());
  std::ifstream in(file);
  std::vector<std::string> lines;
  std::size_t target = 0;
  for (std::string l; std::getline(in, l);) {
    lines.push_back(l);
    if (!target && l.rfind(prefix, 0) == 0) target = lines.size();
  }
  in.close();
  ASSERT_GT(target, 0u);
  lines[target - 1] = text;
  std::ofstream out(file);
  for (const auto& l : lines) out << l << '\n';
  out.close();
  try {
    mapping::loadMiniMapGraph(file.string());
    ADD_FAILURE() << name << ": must be refused";
  } catch (const io::MapFormatError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find(file.string() + ":" + std::to_string(target) + ":"), std::string::npos) << message;
    EXPECT_NE(message.find(what), std::string::npos) << message;
  }
}

/// A well-formed EDGE record (identity pose and covariance) but for what the test puts in.
std::string edgeLine(std::size_t from, std::size_t to, const std::string& kind) {
  std::string line =
      "EDGE " + std::to_string(from) + " " + std::to_string(to) + " " + kind + " covariance 0 0 0 0 1 0 0 0";
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) line += r == c ? " 1" : " 0";
  return line;
}

TEST(MiniMapGraph, CorruptFilesAreRefusedNamingFileAndLine) {
  expectCorruptLineRefused("bad_kind", "EDGE 0 2", edgeLine(0, 2, "sideways"), "sideways");
  expectCorruptLineRefused("unknown_node", "EDGE 0 2", edgeLine(0, 9, "loop"), "unknown mini-map");
  expectCorruptLineRefused("bad_quaternion", "NODE 1", "NODE 1 0 0 0 0 2 0 0 0", "unit length");
  expectCorruptLineRefused("orphan_observation", "LANDMARK 0", "LANDMARK 0 1 0 0 1 1 0 0 0 1 0 0 0 1 1 77 3 4",
                           "frame 77");
  expectCorruptLineRefused("short_record", "FRAME 0", "FRAME 0 1 2", "fields");
  expectCorruptLineRefused("header", "WICP_MINIMAP_GRAPH", "WICP_MINIMAP_GRAPH 7", "version");
  // Found by fuzz_minimap_graph: a record too short to name its node threw std::out_of_range.
  expectCorruptLineRefused("no_node_field", "LANDMARK 0", "LANDMARK", "field 2 is missing");
  // 16 + 3 n wraps round to 20 fields for this n: the record was read past its end.
  expectCorruptLineRefused("wrapping_count", "LANDMARK 0",
                           "LANDMARK 0 1 0 0 1 1 0 0 0 1 0 0 0 1 12297829382473034412 0 3 4 5", "does not match");
  EXPECT_THROW(mapping::loadMiniMapGraph((scratchDir("missing") / "none.txt").string()), io::MapFormatError);
}

TEST(MiniMapGraph, ExportsTheMergedMapAsPaperFormatAndWeightedCloud) {
  const mapping::MiniMapGraph graph = graphWithLoop();
  const fs::path dir = scratchDir("export");
  mapping::exportMergedMap(graph, (dir / "map.txt").string());
  const LandmarkMap text = io::readLandmarkMap((dir / "map.txt").string());
  EXPECT_EQ(text.landmarks.size(), graph.mergedMap().landmarks.size());
  mapping::exportMergedMap(graph, (dir / "map.ply").string());
  const auto cloud = io::loadLandmarkCloud((dir / "map.ply").string());
  ASSERT_EQ(cloud->size(), text.landmarks.size());
  const auto weights = computeWeights(text, CovarianceWeight{});
  for (std::size_t i = 0; i < cloud->size(); ++i) EXPECT_NEAR((*cloud)[i].weight, weights[i], 1e-6);
  EXPECT_THROW(mapping::exportMergedMap(graph, (dir / "map.obj").string()), std::runtime_error);
  EXPECT_FALSE(fs::exists(dir / "map.obj"));
}

TEST(MiniMapGraph, MergedMapKeepsSessionsApart) {
  mapping::MiniMapGraph graph;
  for (std::size_t session = 0; session < 2; ++session) {
    mapping::MiniMapNode node;
    node.session = session;
    node.landmarks.frames[0] = Eigen::Isometry3d::Identity();
    Landmark landmark;
    landmark.id = 3;
    landmark.observations.push_back({0, 1.0, 2.0});
    node.landmarks.landmarks.push_back(landmark);
    graph.addNode(node);
  }
  const LandmarkMap merged = graph.mergedMap();
  EXPECT_EQ(merged.frames.size(), 2u);
  ASSERT_EQ(merged.landmarks.size(), 2u);
  EXPECT_EQ(merged.landmarks[1].id, 3 + mapping::MiniMapGraph::kSessionIdStride);
}

TEST(MiniMapGraph, AnchorOptimisationClosesADriftedLoopOfMiniMaps) {
  const DriftedLoop loop = makeDriftedLoop(30, 3.0, 0.2, 0.005);
  mapping::MiniMapGraph graph;
  for (const auto& pose : loop.drifted) {
    mapping::MiniMapNode node;
    node.anchor_wc = pose;
    graph.addNode(node);
  }
  for (std::size_t i = 0; i + 1 < loop.drifted.size(); ++i) {
    mapping::MiniMapEdge edge;
    edge.from = i;
    edge.to = i + 1;
    edge.to_in_from = loop.odometry[i];
    edge.covariance = mapping::odometryInformation(edge.to_in_from, {}).inverse();
    graph.addEdge(edge);
  }
  mapping::MiniMapEdge closing;
  closing.from = 0;
  closing.to = 29;
  closing.kind = mapping::MiniMapEdgeKind::Loop;
  closing.strategy = "covariance";
  closing.to_in_from = loop.truth[0].inverse() * loop.truth[29];
  graph.addEdge(closing);
  const auto summary = graph.optimizeAnchors();
  ASSERT_TRUE(summary.ok);
  EXPECT_EQ(summary.loops_used, 1u);
  std::vector<Eigen::Isometry3d> anchors;
  for (const auto& node : graph.nodes()) anchors.push_back(node.anchor_wc);
  EXPECT_LT(rmsPositionError(loop, anchors), rmsPositionError(loop, loop.drifted) / 3);
}

}  // namespace
}  // namespace weighted_icp::testing
