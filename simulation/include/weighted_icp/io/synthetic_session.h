#pragma once
// deprecated: include weighted_icp/simulation/session.h; kept for one release.
// The synthetic SLAM session moved from io to the simulation library (link
// weighted_icp::simulation); these names keep old code compiling.

#include "weighted_icp/io/synthetic_rgbd.h"
#include "weighted_icp/simulation/session.h"

namespace weighted_icp::io {

using simulation::generateSyntheticSession;
using simulation::SyntheticSession;
using simulation::SyntheticSessionOptions;

}  // namespace weighted_icp::io
