#pragma once
// deprecated: include weighted_icp/simulation/rgbd_sequence.h (and
// weighted_icp/simulation/tum_export.h for writeTumSequence); kept for one
// release. The synthetic RGB-D sequence moved from io to the simulation
// library (link weighted_icp::simulation); these names keep old code compiling.

#include "weighted_icp/simulation/rgbd_sequence.h"
#include "weighted_icp/simulation/tum_export.h"

namespace weighted_icp::io {

using simulation::SceneBox;
using simulation::syntheticRgbdCamera;
using simulation::SyntheticRgbdFrame;
using simulation::SyntheticRgbdOptions;
using simulation::SyntheticRgbdSequence;
using simulation::writeTumSequence;

}  // namespace weighted_icp::io
