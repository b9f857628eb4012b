// The mini-map graph: building from a SLAM map, anchor optimisation, merged export, the graph file.
#include "weighted_icp/mapping/minimap_graph.h"

#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>

#include "text_records.h"
#include "weighted_icp/frontend/slam/minimap_builder.h"
#include "weighted_icp/io/atomic_file.h"
#include "weighted_icp/io/cloud_io.h"
#include "weighted_icp/io/map_format.h"
#include "weighted_icp/registration/landmark_point.h"

namespace weighted_icp::mapping {

namespace {

constexpr int kFormatVersion = 1;

bool isSymmetricPositiveDefinite(const Eigen::Matrix<double, 6, 6>& m) {
  return m.allFinite() && m.isApprox(m.transpose(), 1e-9 * std::max(1.0, m.cwiseAbs().maxCoeff())) &&
         m.llt().info() == Eigen::Success && m.ldlt().vectorD().minCoeff() > 0.0;
}

}  // namespace

std::string toString(MiniMapEdgeKind kind) {
  switch (kind) {
    case MiniMapEdgeKind::Sequential: return "sequential";
    case MiniMapEdgeKind::Loop: return "loop";
    case MiniMapEdgeKind::Merge: return "merge";
  }
  return "unknown";
}

MiniMapEdgeKind parseMiniMapEdgeKind(const std::string& name) {
  for (const auto kind : {MiniMapEdgeKind::Sequential, MiniMapEdgeKind::Loop, MiniMapEdgeKind::Merge})
    if (toString(kind) == name) return kind;
  throw std::invalid_argument("edge kind " + detail::echo(name) + " is not one of sequential, loop, merge");
}

LandmarkMap MiniMapNode::inWorld() const {
  LandmarkMap world = landmarks;
  world.transform(anchor_wc);
  return world;
}

MiniMapId MiniMapGraph::addNode(MiniMapNode node) {
  if (!node.anchor_wc.matrix().allFinite()) throw std::invalid_argument("MiniMapGraph: the anchor is not finite");
  node.id = nodes_.size();
  nodes_.push_back(std::move(node));
  return nodes_.back().id;
}

void MiniMapGraph::addEdge(const MiniMapEdge& edge) {
  const std::string name = "MiniMapGraph: edge " + std::to_string(edge.from) + " -> " + std::to_string(edge.to);
  if (edge.from >= nodes_.size() || edge.to >= nodes_.size())
    throw std::invalid_argument(name + " names an unknown mini-map");
  if (edge.from == edge.to) throw std::invalid_argument(name + " joins a mini-map to itself");
  if (edge.strategy.empty() || edge.strategy.find_first_of(" \t\r\n") != std::string::npos)
    throw std::invalid_argument(name + ": the strategy must be one word");
  if (!std::isfinite(edge.fitness) || edge.fitness < 0.0) throw std::invalid_argument(name + ": bad fitness");
  if (!edge.to_in_from.matrix().allFinite()) throw std::invalid_argument(name + ": the relative pose is not finite");
  if (!isSymmetricPositiveDefinite(edge.covariance))
    throw std::invalid_argument(name + ": the covariance is not symmetric positive definite");
  edges_.push_back(edge);
}

MiniMapGraph MiniMapGraph::fromSlamMap(const frontend::Map& map, std::size_t keyframes_per_minimap, std::size_t session,
                                       const OdometryNoiseModel& odometry) {
  const std::vector<LandmarkMap> minimaps = frontend::MiniMapBuilder(keyframes_per_minimap).build(map);
  std::map<frontend::KeyframeId, std::size_t> segment_of;
  for (const auto& keyframe : map.keyframes()) segment_of[keyframe.id] = keyframe.segment;
  MiniMapGraph graph;
  for (const LandmarkMap& minimap : minimaps) {
    if (minimap.frames.empty()) continue;
    MiniMapNode node;
    node.session = session;
    node.anchor_wc = minimap.frames.begin()->second;
    node.landmarks = minimap;
    node.landmarks.transform(node.anchor_wc.inverse());
    const MiniMapId id = graph.addNode(std::move(node));
    if (id == 0) continue;
    const MiniMapNode& previous = graph.nodes_[id - 1];
    MiniMapEdge edge;
    edge.from = id - 1;
    edge.to = id;
    edge.to_in_from = previous.anchor_wc.inverse() * graph.nodes_[id].anchor_wc;
    const bool across_segments = segment_of[previous.landmarks.frames.begin()->first] !=
                                 segment_of[graph.nodes_[id].landmarks.frames.begin()->first];
    edge.covariance = odometryInformation(edge.to_in_from, odometry, across_segments).inverse();
    graph.addEdge(edge);
  }
  return graph;
}

PoseGraphSummary MiniMapGraph::optimizeAnchors(const PoseGraphOptions& options) {
  PoseGraph graph;
  for (const auto& node : nodes_) graph.addNode(node.id, node.anchor_wc, node.id == 0);
  for (const auto& edge : edges_) {
    const Information6d information = edge.covariance.inverse();
    graph.addEdge({edge.from, edge.to, edge.to_in_from, 0.5 * (information + information.transpose()),
                   edge.kind == MiniMapEdgeKind::Sequential ? PoseGraphEdgeKind::Odometry : PoseGraphEdgeKind::Loop});
  }
  const PoseGraphSummary summary = graph.optimize(options);
  if (summary.ok)
    for (auto& node : nodes_) node.anchor_wc = graph.poses().at(node.id);
  return summary;
}

LandmarkMap MiniMapGraph::mergedMap() const {
  LandmarkMap merged;
  std::map<std::uint64_t, std::size_t> index;  // offset landmark id -> position in merged.landmarks
  for (const auto& node : nodes_) {
    const std::uint64_t offset = node.session * kSessionIdStride;
    const LandmarkMap world = node.inWorld();
    for (const auto& [id, pose] : world.frames) merged.frames.emplace(id + offset, pose);
    for (Landmark landmark : world.landmarks) {
      landmark.id += offset;
      for (auto& observation : landmark.observations) observation.frame_id += offset;
      const auto known = index.find(landmark.id);
      if (known == index.end()) {
        index.emplace(landmark.id, merged.landmarks.size());
        merged.landmarks.push_back(std::move(landmark));
      } else {
        // Seen in an earlier mini-map too: one landmark, there, with the observations of both.
        auto& observations = merged.landmarks[known->second].observations;
        observations.insert(observations.end(), landmark.observations.begin(), landmark.observations.end());
      }
    }
  }
  return merged;
}

void saveMiniMapGraph(const MiniMapGraph& graph, const std::string& path) {
  io::writeAtomically(path, [&graph](const std::string& temporary) {
    std::ofstream out(temporary);
    if (!out) throw std::runtime_error("cannot write " + temporary);
    out << "# weighted_icp mini-map graph (docs/mapping.md)\n"
        << "# NODE id session tx ty tz qw qx qy qz            (anchor, camera-to-world)\n"
        << "# FRAME node id tx ty tz qw qx qy qz              (in the anchor frame)\n"
        << "# LANDMARK node id x y z c00..c22 n (frame u v) x n (in the anchor frame)\n"
        << "# EDGE from to kind strategy fitness tx ty tz qw qx qy qz cov(36, row-major)\n"
        << "WICP_MINIMAP_GRAPH " << kFormatVersion << '\n';
    for (const auto& node : graph.nodes()) {
      out << "NODE " << node.id << ' ' << node.session << ' ' << detail::poseFields(node.anchor_wc) << '\n';
      for (const auto& [id, pose] : node.landmarks.frames)
        out << "FRAME " << node.id << ' ' << id << ' ' << detail::poseFields(pose) << '\n';
      for (const auto& landmark : node.landmarks.landmarks) {
        out << "LANDMARK " << node.id << ' ' << landmark.id;
        for (int i = 0; i < 3; ++i) out << ' ' << detail::exact(landmark.position[i]);
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) out << ' ' << detail::exact(landmark.covariance(r, c));
        out << ' ' << landmark.observations.size();
        for (const auto& o : landmark.observations)
          out << ' ' << o.frame_id << ' ' << detail::exact(o.u) << ' ' << detail::exact(o.v);
        out << '\n';
      }
    }
    for (const auto& edge : graph.edges()) {
      out << "EDGE " << edge.from << ' ' << edge.to << ' ' << toString(edge.kind) << ' ' << edge.strategy << ' '
          << detail::exact(edge.fitness) << ' ' << detail::poseFields(edge.to_in_from);
      for (int r = 0; r < 6; ++r)
        for (int c = 0; c < 6; ++c) out << ' ' << detail::exact(edge.covariance(r, c));
      out << '\n';
    }
    out.close();
    if (!out) throw std::runtime_error("error writing " + temporary);
  });
}

namespace {

void readNode(detail::RecordReader& in, MiniMapGraph& graph) {
  in.expectFields(10);
  const std::uint64_t id = in.count(1, "id");
  if (id != graph.nodes().size())
    in.fail("node id " + std::to_string(id) + " out of order (expected " + std::to_string(graph.nodes().size()) + ")");
  MiniMapNode node;
  node.session = in.count(2, "session");
  node.anchor_wc = in.pose(3);
  graph.addNode(std::move(node));
}

/// The node a FRAME or LANDMARK record belongs to: the last NODE read (records of a node follow it).
std::size_t recordNode(const detail::RecordReader& in, const MiniMapGraph& graph) {
  const std::uint64_t node = in.count(1, "node");
  if (graph.nodes().empty() || node != graph.nodes().size() - 1)
    in.fail("record of node " + std::to_string(node) + " outside that node's NODE block");
  return node;
}

void readFrame(detail::RecordReader& in, LandmarkMap& landmarks) {
  in.expectFields(10);
  const FrameId id = in.count(2, "frame id");
  if (!landmarks.frames.emplace(id, in.pose(3)).second) in.fail("frame " + std::to_string(id) + " repeated");
}

void readLandmark(detail::RecordReader& in, LandmarkMap& landmarks) {
  in.expectAtLeast(16);
  Landmark landmark;
  landmark.id = in.count(2, "landmark id");
  landmark.position = Eigen::Vector3d(in.number(3, "x"), in.number(4, "y"), in.number(5, "z"));
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      landmark.covariance(r, c) = in.number(6 + 3 * r + c, "c" + std::to_string(r) + std::to_string(c));
  const std::size_t n = in.count(15, "n");
  // Compared by division: 16 + 3 n can wrap round for a corrupt n and match the record's length.
  if (n != (in.size() - 16) / 3) in.fail("n = " + std::to_string(n) + " does not match the record's fields");
  in.expectFields(16 + 3 * n);
  for (std::size_t o = 0; o < n; ++o) {
    const std::size_t f = 16 + 3 * o;
    Observation observation{in.count(f, "frame"), in.number(f + 1, "u"), in.number(f + 2, "v")};
    if (!landmarks.frames.count(observation.frame_id))
      in.fail("observation by frame " + std::to_string(observation.frame_id) + ", which the node lacks");
    landmark.observations.push_back(observation);
  }
  landmarks.landmarks.push_back(std::move(landmark));
}

void readEdge(detail::RecordReader& in, MiniMapGraph& graph) {
  in.expectFields(6 + 7 + 36);
  MiniMapEdge edge;
  edge.from = in.count(1, "from");
  edge.to = in.count(2, "to");
  try {
    edge.kind = parseMiniMapEdgeKind(std::string(in.field(3)));
  } catch (const std::invalid_argument& error) {
    in.fail(error.what());
  }
  edge.strategy = std::string(in.field(4));
  edge.fitness = in.number(5, "fitness");
  edge.to_in_from = in.pose(6);
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) edge.covariance(r, c) = in.number(13 + 6 * r + c, "covariance");
  try {
    graph.addEdge(edge);
  } catch (const std::invalid_argument& error) {
    in.fail(error.what());
  }
}

}  // namespace

MiniMapGraph loadMiniMapGraph(const std::string& path) {
  detail::RecordReader in(path);
  in.expect("WICP_MINIMAP_GRAPH");
  in.expectFields(2);
  if (in.count(1, "version") != kFormatVersion)
    in.fail("format version " + std::string(in.field(1)) + " is not " + std::to_string(kFormatVersion));
  MiniMapGraph graph;
  std::vector<LandmarkMap> contents;  // filled while reading, moved into the nodes at the end
  bool edges_started = false;
  while (in.next()) {
    const std::string_view keyword = in.field(0);
    if (keyword == "EDGE") {
      edges_started = true;
      readEdge(in, graph);
      continue;
    }
    if (edges_started) in.fail(std::string(keyword) + " record after the EDGE records");
    if (keyword == "NODE") {
      readNode(in, graph);
      contents.emplace_back();
    } else if (keyword == "FRAME") {
      readFrame(in, contents.at(recordNode(in, graph)));
    } else if (keyword == "LANDMARK") {
      readLandmark(in, contents.at(recordNode(in, graph)));
    } else {
      in.fail("unknown record " + detail::echo(keyword));
    }
  }
  MiniMapGraph result;
  for (std::size_t i = 0; i < graph.nodes().size(); ++i) {
    MiniMapNode node = graph.nodes()[i];
    node.landmarks = std::move(contents[i]);
    result.addNode(std::move(node));
  }
  for (const auto& edge : graph.edges()) result.addEdge(edge);
  return result;
}

void exportMergedMap(const MiniMapGraph& graph, const std::string& path, const WeightFunction& weight) {
  const std::string extension = std::filesystem::path(path).extension().string();
  const LandmarkMap merged = graph.mergedMap();
  if (extension == ".txt") {
    io::writeLandmarkMap(merged, path);
  } else if (extension == ".ply" || extension == ".pcd") {
    io::saveLandmarkCloud(*toLandmarkCloud(merged, weight), path);
  } else {
    throw std::runtime_error("exportMergedMap: " + path + ": the extension must be .txt, .ply or .pcd");
  }
}

}  // namespace weighted_icp::mapping
