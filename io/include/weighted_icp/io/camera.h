#pragma once
// Camera files: the TUM presets by name or an OpenCV FileStorage YAML file,
// read and written. The camera model itself is core's
// (weighted_icp/core/camera.h).

#include <string>

#include "weighted_icp/core/camera.h"

namespace weighted_icp::io {

// The model moved to core; these names keep io::PinholeCamera and
// io::tumCamera working for one release.
using weighted_icp::PinholeCamera;
using weighted_icp::tumCamera;

/// @brief "fr1", "fr2", "fr3" or the path of an OpenCV FileStorage YAML with
/// keys fx, fy, cx, cy, k1, k2, p1, p2, k3, width, height, depth_factor, and for depth images not registered
/// to the colour images the depth camera (PinholeCamera::unregistered_depth), all ten keys or none: depth_fx,
/// depth_fy, depth_cx, depth_cy, its position in the colour camera's frame depth_tx, depth_ty, depth_tz (metres,
/// at most 1 m each) and its rotation vector depth_rx, depth_ry, depth_rz (radians, at most pi each); with them,
/// optionally, the depth images' size depth_width and depth_height when it is not the colour images' (both or
/// neither).
/// Throws std::runtime_error naming the file and every missing or invalid key.
/// @param preset_or_path a TUM preset name or a file path
PinholeCamera loadCamera(const std::string& preset_or_path);
/// @brief Writes the YAML form read by loadCamera (atomically).
/// @param camera a valid camera (else std::runtime_error naming the keys)
/// @param path the file to write
void saveCamera(const PinholeCamera& camera, const std::string& path);

/// @brief The camera to read the TUM folder `dataset` with: `spec` when given (fr1|fr2|fr3|FILE.yaml), else the
/// folder's own camera.yaml (what wicp_make_variant and wicp_synthetic_rgbd write), else the TUM sensor named in
/// the folder's name (rgbd_dataset_freiburg3_teddy, tum_fr1_xyz_head). Throws std::runtime_error naming the
/// folder when it does not exist, saying how to pass the camera when none applies, or naming the camera file and
/// its invalid keys.
/// @param dataset the TUM folder
/// @param spec the camera asked for, empty when none
/// @param how_to_pass how the caller's user passes a camera, for the error ("--camera" for the tools)
PinholeCamera datasetCamera(const std::string& dataset, const std::string& spec,
                            const std::string& how_to_pass = "--camera");

}  // namespace weighted_icp::io
