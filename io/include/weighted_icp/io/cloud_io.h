#pragma once
// Weighted landmark clouds as PCD or PLY (binary), chosen by file extension.

#include <string>

#include "weighted_icp/registration/landmark_point.h"

namespace weighted_icp::io {

/// Saves atomically; throws std::runtime_error naming the path and the reason
/// (unknown extension, write failure).
void saveLandmarkCloud(const LandmarkCloud& cloud, const std::string& path);
/// Loads a PCD or PLY with LandmarkPoint's fields; throws std::runtime_error.
LandmarkCloud::Ptr loadLandmarkCloud(const std::string& path);

}  // namespace weighted_icp::io
