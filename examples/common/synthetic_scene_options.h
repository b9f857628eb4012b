#pragma once
// The synthetic scene's command-line options (room, loop, texture, lighting, depth error), defined once for
// every tool that renders or runs the synthetic sequence, so that a scene run by wicp_rgbd_slam can be written
// to disk by wicp_synthetic_rgbd with the same words.

#include <string>

#include <boost/program_options.hpp>

#include "weighted_icp/simulation/rgbd_sequence.h"

namespace weighted_icp::tools {

/// @brief Adds --moving-object, --dim, --frames-per-loop, --depth-distortion, --repeated-texture and --room-scale.
/// @param description where the options go
/// @param options the scene they set (must outlive parsing; its values are the defaults shown)
/// @param help_prefix put before each option's help, e.g. "synthetic: " where other options share the list
void addSyntheticSceneOptions(boost::program_options::options_description& description,
                              simulation::SyntheticRgbdOptions& options, const std::string& help_prefix = "");

}  // namespace weighted_icp::tools
