// Names of the RANSAC PnP solvers, for options and reports.
#include "weighted_icp/frontend/geometry/pnp_method.h"

#include <stdexcept>

namespace weighted_icp::frontend {

std::string toString(PnpMethod method) {
  switch (method) {
    case PnpMethod::Ap3p: return "ap3p";
    case PnpMethod::Iterative: return "iterative";
  }
  return "unknown";
}

PnpMethod parsePnpMethod(const std::string& name) {
  for (const auto method : {PnpMethod::Ap3p, PnpMethod::Iterative})
    if (toString(method) == name) return method;
  throw std::invalid_argument("unknown PnP method '" + name + "' (expected ap3p or iterative)");
}

}  // namespace weighted_icp::frontend
