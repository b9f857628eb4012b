#pragma once
// Shared by the mapping tests and benchmark: a keyframe loop on a circle, its drifted odometry, and the loop edge
// that closes it.

#include <cmath>
#include <cstddef>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "weighted_icp/mapping/pose_graph.h"

namespace weighted_icp::testing {

/// Ground truth and a drifted odometry estimate of `n` keyframes going once round a circle of `radius` metres.
struct DriftedLoop {
  std::vector<Eigen::Isometry3d> truth;     // camera-to-world
  std::vector<Eigen::Isometry3d> odometry;  // measured relative poses, i -> i+1 (pose of i+1 in i)
  std::vector<Eigen::Isometry3d> drifted;   // the odometry chained from truth[0]
};

inline Eigen::Isometry3d poseOnCircle(double angle, double radius) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(radius * std::cos(angle), radius * std::sin(angle), 0.1 * std::sin(3 * angle));
  // Looking outwards, camera z along the radius, y down.
  pose.linear() = Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
                  Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();
  return pose;
}

/// Odometry with a systematic yaw bias (`yaw_bias_deg` per step, the drift) and random noise (`noise_m`, metres,
/// and a tenth of a degree per axis): what the drift-correction tests need to undo.
inline DriftedLoop makeDriftedLoop(std::size_t n, double radius, double yaw_bias_deg, double noise_m,
                                   unsigned seed = 7) {
  DriftedLoop loop;
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (std::size_t i = 0; i < n; ++i) loop.truth.push_back(poseOnCircle(2 * M_PI * i / n, radius));
  loop.drifted.push_back(loop.truth[0]);
  for (std::size_t i = 0; i + 1 < n; ++i) {
    Eigen::Isometry3d relative = loop.truth[i].inverse() * loop.truth[i + 1];
    Eigen::Isometry3d error = Eigen::Isometry3d::Identity();
    const Eigen::Vector3d small_rotation(gauss(rng), gauss(rng), gauss(rng));
    error.linear() = (Eigen::AngleAxisd(yaw_bias_deg * M_PI / 180, Eigen::Vector3d::UnitY()) *
                      Eigen::AngleAxisd(0.1 * M_PI / 180 * small_rotation.norm(), small_rotation.normalized()))
                         .toRotationMatrix();
    error.translation() = noise_m * Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng));
    relative = relative * error;
    loop.odometry.push_back(relative);
    loop.drifted.push_back(loop.drifted.back() * relative);
  }
  return loop;
}

/// The pose graph of the drifted chain: nodes at the drifted poses (the first fixed), odometry edges.
inline mapping::PoseGraph makeOdometryGraph(const DriftedLoop& loop, const mapping::OdometryNoiseModel& model = {}) {
  mapping::PoseGraph graph;
  for (std::size_t i = 0; i < loop.drifted.size(); ++i) graph.addNode(i, loop.drifted[i], i == 0);
  for (std::size_t i = 0; i < loop.odometry.size(); ++i)
    graph.addEdge({i, i + 1, loop.odometry[i], mapping::odometryInformation(loop.odometry[i], model),
                   mapping::PoseGraphEdgeKind::Odometry});
  return graph;
}

/// A loop edge between keyframes `match` < `query` measuring their true relative pose, moved by `error`.
inline mapping::PoseGraphEdge trueLoopEdge(const DriftedLoop& loop, std::size_t match, std::size_t query,
                                           const Eigen::Isometry3d& error = Eigen::Isometry3d::Identity()) {
  mapping::PoseGraphEdge edge;
  edge.from = match;
  edge.to = query;
  edge.to_in_from = loop.truth[match].inverse() * loop.truth[query] * error;
  edge.information.diagonal() << 1e4, 1e4, 1e4, 1e4, 1e4, 1e4;  // 1 cm, 0.6 degrees
  edge.kind = mapping::PoseGraphEdgeKind::Loop;
  return edge;
}

/// Root mean square position error of `poses` against the loop's truth.
inline double rmsPositionError(const DriftedLoop& loop, const std::vector<Eigen::Isometry3d>& poses) {
  double sum = 0.0;
  for (std::size_t i = 0; i < poses.size(); ++i)
    sum += (poses[i].translation() - loop.truth[i].translation()).squaredNorm();
  return std::sqrt(sum / static_cast<double>(poses.size()));
}

inline std::vector<Eigen::Isometry3d> posesOf(const mapping::PoseGraph& graph) {
  std::vector<Eigen::Isometry3d> poses;
  for (const auto& [id, pose] : graph.poses()) poses.push_back(pose);
  return poses;
}

}  // namespace weighted_icp::testing
