#pragma once
// The Ceres settings every geometry solve shares (private to this layer).

#include <ceres/ceres.h>

namespace weighted_icp::frontend::detail {

/// Levenberg-Marquardt, dense QR, one thread (reproducible), silent.
inline ceres::Solver::Options levenbergMarquardt(int max_iterations) {
  ceres::Solver::Options options;
  options.minimizer_type = ceres::TRUST_REGION;
  options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = max_iterations;
  options.num_threads = 1;
  options.logging_type = ceres::SILENT;
  return options;
}

}  // namespace weighted_icp::frontend::detail
