#pragma once
// Deprecated path, kept for one release: the header moved to the slam layer's
// folder, which mirrors frontend/src/slam/.
#include "weighted_icp/frontend/slam/rgbd_slam.h"
