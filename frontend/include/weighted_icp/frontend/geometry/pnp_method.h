#pragma once
// Which RANSAC PnP finds the pose PnP refinement starts from: today's AP3P
// minimal sets, or the iterative solution the front-end paper names.

#include <string>

namespace weighted_icp::frontend {

/// @brief The solver inside cv::solvePnPRansac (the Huber Levenberg-Marquardt refinement follows either).
enum class PnpMethod {
  /// 4-point AP3P minimal sets, EPnP on the consensus (the default before issue #11).
  Ap3p,
  /// The front-end paper: "To develop a unique solution to the PnP issue, we use an iterative
  /// 5-point solution." cv::SOLVEPNP_ITERATIVE in cv::solvePnPRansac: OpenCV draws 5-point
  /// minimal sets (solved by EPnP) and fits the consensus by its iterative Levenberg-Marquardt.
  Iterative
};

/// @brief "ap3p" or "iterative".
/// @param method the method to name
std::string toString(PnpMethod method);
/// @brief The method named by toString; std::invalid_argument listing the names otherwise.
/// @param name the name
PnpMethod parsePnpMethod(const std::string& name);

}  // namespace weighted_icp::frontend
