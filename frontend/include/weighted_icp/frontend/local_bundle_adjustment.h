#pragma once
// Deprecated path, kept for one release: the header moved to the geometry layer's
// folder, which mirrors frontend/src/geometry/.
#include "weighted_icp/frontend/geometry/local_bundle_adjustment.h"
