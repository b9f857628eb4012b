#pragma once
// Deprecated path, kept for one release: the header moved to the perception layer's
// folder, which mirrors frontend/src/perception/.
#include "weighted_icp/frontend/perception/descriptor_matcher.h"
