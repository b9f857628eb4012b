#pragma once
// The paper's hierarchical map: a graph whose nodes are mini-maps (a weighted
// landmark map in its own anchor frame, the keyframes it spans, the anchor's
// pose in the world) and whose edges are the alignments between them
// (sequential, loop, merge) with the strategy, fitness and covariance of the
// alignment. Saved and loaded as one text file (docs/mapping.md), exported as
// one merged map (the paper's format, or a weighted PLY/PCD cloud).

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "weighted_icp/frontend/slam/map.h"
#include "weighted_icp/mapping/pose_graph.h"
#include "weighted_icp/registration/landmark_map.h"
#include "weighted_icp/registration/weight_strategies.h"

namespace weighted_icp::mapping {

/// @brief Identifier of a mini-map in a MiniMapGraph.
using MiniMapId = std::size_t;

/// @brief One mini-map: landmarks and keyframe poses in the anchor frame, and the anchor in the world.
struct MiniMapNode {
  /// @brief Assigned by MiniMapGraph::addNode (0, 1, 2, ...).
  MiniMapId id = 0;
  /// @brief The session it comes from (0 for a single run; merges number their sessions).
  std::size_t session = 0;
  /// @brief Camera-to-world pose of the anchor frame (the mini-map's first keyframe when built from a SLAM map).
  Eigen::Isometry3d anchor_wc = Eigen::Isometry3d::Identity();
  /// @brief Keyframe poses (frames, ids = keyframe ids) and landmarks, in the anchor frame.
  LandmarkMap landmarks;

  /// @brief The mini-map in the world frame (landmarks transformed by the anchor).
  LandmarkMap inWorld() const;
};

/// @brief What an edge between two mini-maps records.
enum class MiniMapEdgeKind {
  Sequential,  ///< consecutive mini-maps of one session
  Loop,        ///< a revisit within a session
  Merge        ///< two sessions joined
};
/// @brief "sequential", "loop", "merge".
std::string toString(MiniMapEdgeKind kind);
/// @brief Inverse of toString; throws std::invalid_argument listing the names.
MiniMapEdgeKind parseMiniMapEdgeKind(const std::string& name);

/// @brief An alignment between two mini-maps: the anchor of `to` in the anchor frame of `from`.
struct MiniMapEdge {
  MiniMapId from = 0;
  MiniMapId to = 0;
  MiniMapEdgeKind kind = MiniMapEdgeKind::Sequential;
  /// @brief x_from = to_in_from * x_to.
  Eigen::Isometry3d to_in_from = Eigen::Isometry3d::Identity();
  /// @brief How it was found: a weight strategy name of the weighted ICP ("covariance", ...), "odometry" for a
  /// sequential edge taken from tracking, "pnp" for a loop verified by PnP alone. One token, no spaces.
  std::string strategy = "odometry";
  /// @brief PCL fitness score of the alignment (mean squared nearest-neighbour distance, m^2); 0 if none.
  double fitness = 0.0;
  /// @brief Covariance of to_in_from, ordered (translation, rotation) as PoseGraphEdge's information.
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Identity() * 1e-4;
};

/// @brief The hierarchical map.
class MiniMapGraph {
 public:
  using Ptr = std::shared_ptr<MiniMapGraph>;
  using ConstPtr = std::shared_ptr<const MiniMapGraph>;

  /// @brief Adds a mini-map and returns its id; throws std::invalid_argument for a non-finite anchor.
  /// @param node The mini-map (its id is ignored).
  MiniMapId addNode(MiniMapNode node);
  /// @brief Adds an edge; throws std::invalid_argument for an unknown node, equal ends, an empty or spaced
  /// strategy, a negative or non-finite fitness, a non-finite pose or a covariance that is not symmetric
  /// positive definite.
  /// @param edge The alignment.
  void addEdge(const MiniMapEdge& edge);

  /// @brief Mini-maps of up to `keyframes_per_minimap` keyframes of one SLAM map (never across a tracking loss,
  /// as frontend::MiniMapBuilder cuts them), anchored at their first keyframe, joined by sequential edges that
  /// carry the tracked relative pose and the odometry model's covariance.
  /// @param map The front end's map.
  /// @param keyframes_per_minimap At least 1 (std::invalid_argument otherwise).
  /// @param session The session number the nodes get.
  /// @param odometry The noise model of the sequential edges.
  static MiniMapGraph fromSlamMap(const frontend::Map& map, std::size_t keyframes_per_minimap, std::size_t session = 0,
                                  const OdometryNoiseModel& odometry = {});

  /// @brief Optimises the anchors as a pose graph (sequential edges always kept, loop and merge edges through the
  /// chi-square gate); the first node is fixed.
  /// @param options See PoseGraphOptions.
  PoseGraphSummary optimizeAnchors(const PoseGraphOptions& options = {});

  /// @brief All mini-maps in the world frame as one map. A landmark in several mini-maps of a session (its
  /// observations span them) appears once, at its position in the first of them, with all its observations.
  /// Frame and landmark ids of session s are offset by s * kSessionIdStride so that sessions never collide.
  LandmarkMap mergedMap() const;

  /// @brief The nodes, by id.
  const std::vector<MiniMapNode>& nodes() const { return nodes_; }
  /// @brief The edges, in addEdge order.
  const std::vector<MiniMapEdge>& edges() const { return edges_; }
  /// @brief "MiniMapGraph".
  static std::string getClassName() { return "MiniMapGraph"; }

  /// @brief Offset between the frame and landmark ids of consecutive sessions in mergedMap().
  static constexpr std::uint64_t kSessionIdStride = 1000000000ULL;

 private:
  std::vector<MiniMapNode> nodes_;
  std::vector<MiniMapEdge> edges_;
};

/// @brief Writes the graph as one text file (docs/mapping.md), atomically (io::writeAtomically).
/// @param graph The graph.
/// @param path The file.
void saveMiniMapGraph(const MiniMapGraph& graph, const std::string& path);

/// @brief Reads a graph file; throws io::MapFormatError naming the file and line of the first bad record.
/// @param path The file saveMiniMapGraph wrote.
MiniMapGraph loadMiniMapGraph(const std::string& path);

/// @brief Writes mergedMap() by extension: ".txt" the paper's map format (io/map_format.h), ".ply"/".pcd" a
/// weighted landmark cloud (io/cloud_io.h) with `weight`. Atomic; throws std::runtime_error for another extension.
/// @param graph The graph.
/// @param path The output file.
/// @param weight The weight of each landmark in a cloud (ignored for ".txt").
void exportMergedMap(const MiniMapGraph& graph, const std::string& path,
                     const WeightFunction& weight = CovarianceWeight{});

}  // namespace weighted_icp::mapping
