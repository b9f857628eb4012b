#pragma once
// Export of a synthetic RGB-D sequence in the TUM RGB-D benchmark's folder
// layout, so that tools reading TUM sequences (io::TumSequence, the
// benchmark's scripts) run on it as on recorded data.

#include <cstddef>
#include <functional>
#include <string>

#include "weighted_icp/simulation/rgbd_sequence.h"

namespace weighted_icp::simulation {

/// @brief Writes the sequence in the TUM RGB-D layout: rgb/ and depth/ (PNG,
/// named by timestamp with microseconds), rgb.txt and depth.txt (the same
/// timestamps), groundtruth.txt (camera-to-world, written by
/// io::writeTrajectory: reads back the exact poses at the listed timestamps)
/// and camera.yaml (the rendering camera, io::saveCamera), which the tools read.
/// The folder appears complete or not at all: it is written beside `dir` under
/// a temporary name and renamed at the end.
/// @param sequence what to render
/// @param dir the folder to write; an existing non-empty one is refused
///        (std::runtime_error) unless `overwrite`
/// @param overwrite replace a non-empty `dir`
/// @param frame_written called with i after each frame i, for progress
void writeTumSequence(const SyntheticRgbdSequence& sequence, const std::string& dir, bool overwrite = false,
                      const std::function<void(std::size_t)>& frame_written = {});

}  // namespace weighted_icp::simulation
