// Names of the RANSAC PnP solvers, for options and reports.
#include "weighted_icp/frontend/geometry/pnp_method.h"

#include <stdexcept>

#include "weighted_icp/core/named_values.h"

namespace weighted_icp::frontend {

std::string toString(PnpMethod method) {
  switch (method) {
    case PnpMethod::Ap3p: return "ap3p";
    case PnpMethod::Iterative: return "iterative";
  }
  return "unknown";
}

PnpMethod parsePnpMethod(const std::string& name) {
  return parseNamedValue(
      name, {PnpMethod::Ap3p, PnpMethod::Iterative}, [](auto value) { return toString(value); }, "PnP method");
}

}  // namespace weighted_icp::frontend
