#pragma once
// Which camera a TUM folder was recorded with, for the tools that read one.

#include <string>

#include "weighted_icp/core/camera.h"

namespace weighted_icp::tools {

/// @brief The camera to read `dataset` with: `spec` when given (fr1|fr2|fr3|FILE.yaml),
/// else the folder's own camera.yaml (what wicp_make_variant writes), else the
/// TUM sensor named in the folder's name (rgbd_dataset_freiburg3_teddy,
/// tum_fr1_xyz_head). Throws std::runtime_error when none applies, saying to pass
/// --camera, or naming the camera file and its invalid keys.
/// @param dataset the TUM folder
/// @param spec the --camera value, empty when not given
PinholeCamera datasetCamera(const std::string& dataset, const std::string& spec);

}  // namespace weighted_icp::tools
