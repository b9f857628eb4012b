#pragma once
// The tools' frame-range lists ("0-119,120-239"): wicp_map cut --ranges, wicp_global_sweep --inside.

#include <string>
#include <vector>

#include "weighted_icp/registration/landmark_map.h"

namespace weighted_icp::tools {

/// @brief Frames FIRST-LAST, both included.
struct FrameRange {
  FrameId first = 0;
  FrameId last = 0;
};

/// @brief Parses "FIRST-LAST,FIRST-LAST,..." (ranges may overlap).
/// @param text    the option's value
/// @param option  its name, for the error: a boost::program_options::error (a command-line error, exit 2) naming
///                the option and the range that is not FIRST-LAST with frame ids FIRST <= LAST
std::vector<FrameRange> parseFrameRanges(const std::string& text, const std::string& option);

}  // namespace weighted_icp::tools
