// Pose-graph optimisation: relative-pose residuals on SE(3), LM in Ceres, loop edges admitted by a chi-square test.
#include "weighted_icp/mapping/pose_graph.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <stdexcept>
#include <string>

#include <ceres/ceres.h>
#include <ceres/manifold.h>
#include <boost/math/distributions/chi_squared.hpp>

namespace weighted_icp::mapping {

namespace {

/// Residual of one edge: (R_from^T (p_to - p_from) - t_meas, 2 vec(q_meas^-1 q_from^-1 q_to)), whitened.
struct RelativePoseError {
  Eigen::Vector3d translation;
  Eigen::Quaterniond rotation;
  Eigen::Matrix<double, 6, 6> sqrt_information;

  template <typename T>
  bool operator()(const T* p_from_ptr, const T* q_from_ptr, const T* p_to_ptr, const T* q_to_ptr,
                  T* residuals_ptr) const {
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> p_from(p_from_ptr), p_to(p_to_ptr);
    const Eigen::Map<const Eigen::Quaternion<T>> q_from(q_from_ptr), q_to(q_to_ptr);
    const Eigen::Quaternion<T> q_from_inverse = q_from.conjugate();
    const Eigen::Matrix<T, 3, 1> estimated_translation = q_from_inverse * (p_to - p_from);
    Eigen::Quaternion<T> error = rotation.cast<T>().conjugate() * (q_from_inverse * q_to);
    // q and -q are one rotation: take the one near identity so the error is small when the poses agree.
    if (error.w() < T(0)) error.coeffs() = -error.coeffs();
    Eigen::Map<Eigen::Matrix<T, 6, 1>> residuals(residuals_ptr);
    residuals.template head<3>() = estimated_translation - translation.cast<T>();
    residuals.template tail<3>() = T(2.0) * error.vec();
    residuals.applyOnTheLeft(sqrt_information.cast<T>());
    return true;
  }
};

/// Position and quaternion of a pose, in the layout the residual reads.
struct NodeState {
  Eigen::Vector3d position;
  Eigen::Quaterniond rotation;
};

bool isSymmetricPositiveDefinite(const Information6d& information) {
  if (!information.allFinite()) return false;
  if (!information.isApprox(information.transpose(), 1e-9 * std::max(1.0, information.cwiseAbs().maxCoeff())))
    return false;
  return Eigen::LLT<Information6d>(information).info() == Eigen::Success &&
         information.ldlt().vectorD().minCoeff() > 0.0;
}

}  // namespace

PoseGraphEdge loopEdge(const LoopConstraint& loop) {
  PoseGraphEdge edge;
  edge.from = loop.match;
  edge.to = loop.query;
  edge.to_in_from = loop.query_in_match;
  edge.information = loop.information;
  edge.kind = PoseGraphEdgeKind::Loop;
  return edge;
}

Information6d odometryInformation(const Eigen::Isometry3d& relative, const OdometryNoiseModel& model,
                                  bool across_segments) {
  const double distance = relative.translation().norm();
  const double angle = Eigen::AngleAxisd(relative.linear()).angle();
  const double sigma_t = model.translation_sigma_m + model.translation_sigma_per_m * distance;
  const double sigma_r = model.rotation_sigma_rad + model.rotation_sigma_per_rad * angle;
  Information6d information = Information6d::Zero();
  information.diagonal().head<3>().setConstant(1.0 / (sigma_t * sigma_t));
  information.diagonal().tail<3>().setConstant(1.0 / (sigma_r * sigma_r));
  if (across_segments) information /= model.segment_break_factor;
  return information;
}

void PoseGraph::addNode(frontend::KeyframeId id, const Eigen::Isometry3d& pose_wc, bool fixed) {
  if (!pose_wc.matrix().allFinite())
    throw std::invalid_argument("PoseGraph: node " + std::to_string(id) + " has a non-finite pose");
  poses_[id] = pose_wc;
  fixed_[id] = fixed;
}

void PoseGraph::addEdge(const PoseGraphEdge& edge) {
  const std::string name = "PoseGraph: edge " + std::to_string(edge.from) + " -> " + std::to_string(edge.to);
  if (!poses_.count(edge.from) || !poses_.count(edge.to)) throw std::invalid_argument(name + " names an unknown node");
  if (edge.from == edge.to) throw std::invalid_argument(name + " joins a node to itself");
  if (!edge.to_in_from.matrix().allFinite()) throw std::invalid_argument(name + " has a non-finite relative pose");
  if (!isSymmetricPositiveDefinite(edge.information))
    throw std::invalid_argument(name + ": the information matrix is not symmetric positive definite");
  edges_.push_back(edge);
}

namespace {

/// Levenberg-Marquardt over a sparse normal Cholesky, silent, with the options' iterations and threads.
ceres::Solver::Options solverOptions(const PoseGraphOptions& options) {
  ceres::Solver::Options solver;
  solver.minimizer_type = ceres::TRUST_REGION;
  solver.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  solver.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  solver.max_num_iterations = options.max_iterations;
  solver.num_threads = std::max(1, options.threads);
  solver.logging_type = ceres::SILENT;
  return solver;
}

}  // namespace

PoseGraph::Solve PoseGraph::solve(const std::vector<bool>& use,
                                  std::map<frontend::KeyframeId, Eigen::Isometry3d>& poses,
                                  const PoseGraphOptions& options) const {
  std::map<frontend::KeyframeId, NodeState> states;
  for (const auto& [id, pose] : poses) states[id] = {pose.translation(), Eigen::Quaterniond(pose.linear())};

  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  ceres::EigenQuaternionManifold quaternion_manifold;
  ceres::HuberLoss loop_loss(options.loop_huber);
  std::set<frontend::KeyframeId> in_problem;
  for (std::size_t e = 0; e < edges_.size(); ++e) {
    if (!use[e]) continue;
    const PoseGraphEdge& edge = edges_[e];
    const Eigen::Matrix<double, 6, 6> sqrt_information = edge.information.llt().matrixU();
    auto* cost = new ceres::AutoDiffCostFunction<RelativePoseError, 6, 3, 4, 3, 4>(new RelativePoseError{
        edge.to_in_from.translation(), Eigen::Quaterniond(edge.to_in_from.linear()), sqrt_information});
    NodeState& from = states.at(edge.from);
    NodeState& to = states.at(edge.to);
    problem.AddResidualBlock(cost, edge.kind == PoseGraphEdgeKind::Loop ? &loop_loss : nullptr, from.position.data(),
                             from.rotation.coeffs().data(), to.position.data(), to.rotation.coeffs().data());
    for (const frontend::KeyframeId id : {edge.from, edge.to})
      if (in_problem.insert(id).second)
        problem.SetManifold(states.at(id).rotation.coeffs().data(), &quaternion_manifold);
  }
  if (in_problem.empty()) return {true, "", 0.0};

  // The gauge: the fixed nodes, or the smallest id of the problem.
  bool any_fixed = false;
  for (const frontend::KeyframeId id : in_problem)
    if (fixed_.at(id)) {
      problem.SetParameterBlockConstant(states.at(id).position.data());
      problem.SetParameterBlockConstant(states.at(id).rotation.coeffs().data());
      any_fixed = true;
    }
  if (!any_fixed) {
    NodeState& first = states.at(*in_problem.begin());
    problem.SetParameterBlockConstant(first.position.data());
    problem.SetParameterBlockConstant(first.rotation.coeffs().data());
  }

  ceres::Solver::Summary summary;
  ceres::Solve(solverOptions(options), &problem, &summary);
  if (!summary.IsSolutionUsable()) return {false, summary.message, 0.0};
  for (const frontend::KeyframeId id : in_problem) {
    const NodeState& state = states.at(id);
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = state.rotation.normalized().toRotationMatrix();
    pose.translation() = state.position;
    poses[id] = pose;
  }
  return {true, "", summary.final_cost};
}

namespace {

/// The chi-square gate of `dof` degrees of freedom at the probability loop_chi2_gate has for one loop's six.
/// A gate of 0 or less admits nothing, an infinite one (or one whose probability rounds to 1) everything, as for one
/// loop.
double jointLoopGate(double six_dof_gate, std::size_t dof) {
  if (!(six_dof_gate > 0.0)) return 0.0;
  if (!std::isfinite(six_dof_gate)) return six_dof_gate;
  const double probability = boost::math::cdf(boost::math::chi_squared_distribution<double>(6.0), six_dof_gate);
  if (!(probability < 1.0)) return std::numeric_limits<double>::infinity();
  return boost::math::quantile(boost::math::chi_squared_distribution<double>(static_cast<double>(dof)), probability);
}

}  // namespace

void PoseGraph::admitEarlierLoopsTogether(const PoseGraphOptions& options, PoseGraphSummary& summary,
                                          std::map<frontend::KeyframeId, Eigen::Isometry3d>& poses,
                                          Solve& current) const {
  std::vector<bool> trial = summary.edge_used;
  std::size_t earlier = 0;
  for (std::size_t e = 0; e < edges_.size(); ++e)
    if (edges_[e].kind == PoseGraphEdgeKind::Loop && edges_[e].admitted_before) {
      trial[e] = true;
      ++earlier;
    }
  if (earlier < 2) return;  // one alone is tested as any loop is
  std::map<frontend::KeyframeId, Eigen::Isometry3d> trial_poses = poses;
  const Solve attempt = solve(trial, trial_poses, options);
  ++summary.solves;
  if (!attempt.ok || 2.0 * (attempt.cost - current.cost) > jointLoopGate(options.loop_chi2_gate, 6 * earlier)) return;
  summary.edge_used = std::move(trial);
  summary.loops_used += earlier;
  poses = std::move(trial_poses);
  current = attempt;
}

PoseGraphSummary PoseGraph::optimize(const PoseGraphOptions& options) {
  PoseGraphSummary summary;
  summary.edge_used.assign(edges_.size(), false);
  for (std::size_t e = 0; e < edges_.size(); ++e) summary.edge_used[e] = edges_[e].kind == PoseGraphEdgeKind::Odometry;

  std::map<frontend::KeyframeId, Eigen::Isometry3d> poses = poses_;
  Solve current = solve(summary.edge_used, poses, options);
  ++summary.solves;
  if (!current.ok) {
    summary.message = "odometry solve failed: " + current.message;
    return summary;
  }
  admitEarlierLoopsTogether(options, summary, poses, current);
  // Each loop is tried on top of the graph so far: a consistent loop raises the optimum's cost by about its
  // degrees of freedom, a wrong one by far more, whatever the drift it corrects. Loops already used were admitted
  // together just above.
  for (std::size_t e = 0; e < edges_.size(); ++e) {
    if (edges_[e].kind != PoseGraphEdgeKind::Loop || summary.edge_used[e]) continue;
    std::vector<bool> trial = summary.edge_used;
    trial[e] = true;
    std::map<frontend::KeyframeId, Eigen::Isometry3d> trial_poses = poses;
    const Solve attempt = solve(trial, trial_poses, options);
    ++summary.solves;
    if (attempt.ok && 2.0 * (attempt.cost - current.cost) <= options.loop_chi2_gate) {
      summary.edge_used = trial;
      poses = std::move(trial_poses);
      current = attempt;
      ++summary.loops_used;
    } else {
      ++summary.loops_rejected;
    }
  }
  poses_ = std::move(poses);
  summary.ok = true;
  summary.final_cost = current.cost;
  return summary;
}

}  // namespace weighted_icp::mapping
