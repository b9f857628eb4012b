// The front end's named choices (matcher, quality gate, the papers' techniques) set by wicp_rgbd_slam's option
// names, so that the tool, the Python module and the benchmarks share one table of keys.
#pragma once

#include <string>
#include <vector>

#include "weighted_icp/frontend/slam/frontend.h"

namespace weighted_icp::frontend {

/// @brief Sets one named choice of `options` as wicp_rgbd_slam's option of the same name does ("pnp" ->
/// pnp.method, "quality-measure" -> quality.measure, ...), reading the value with the library's own parser.
/// @param options the options to change
/// @param key     an option name from frontendChoiceKeys()
/// @param value   a name that option accepts ("iterative", "brisque", ...)
/// @throws std::invalid_argument "unknown front-end option '<key>' (expected ...)" or "<key>: unknown ..."
void setFrontendChoice(FrontendOptions& options, const std::string& key, const std::string& value);

/// @brief The word `options` holds for one named choice, the inverse of setFrontendChoice: setting that word back
/// leaves the options as they were ("feature-width" -> "full" or "427-960", "gate-free-retry" -> "on" or "off").
/// @param options the options to read
/// @param key     an option name from frontendChoiceKeys()
/// @throws std::invalid_argument "unknown front-end option '<key>' (expected ...)"
std::string frontendChoiceWord(const FrontendOptions& options, const std::string& key);

/// @brief The keys setFrontendChoice accepts, in the order its messages list them.
std::vector<std::string> frontendChoiceKeys();

}  // namespace weighted_icp::frontend
