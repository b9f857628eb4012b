#pragma once
// What every fuzz target shares: the input as a file (most parsers read paths), and the rule every parser keeps.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace weighted_icp::fuzz {

/// @brief This process's scratch folder (in the system's temporary folder, named after the process id so two
/// fuzzers running side by side never share files); created on first use and removed when the process exits.
const std::filesystem::path& scratchFolder();

/// @brief Writes `bytes` to scratchFolder()/name, replacing what an earlier input left there.
/// @param name a file name (may include sub-folders, created as needed)
/// @param bytes the file's whole content
/// @return the path written
std::string writeInput(const std::string& name, std::string_view bytes);

/// @brief Splits a fuzz input into at most `parts` parts at the separator line "\n@@\n", so that one input can
/// stand for several files (rgb.txt, depth.txt, groundtruth.txt); missing parts are absent, not empty.
/// @param bytes the input
/// @param parts the largest number of parts returned
std::vector<std::string_view> splitParts(std::string_view bytes, std::size_t parts);

/// @brief The rule every parser keeps, checked on one input: `parse` either succeeds or throws
/// std::runtime_error (or a class derived from it) whose message names `source` and is short (a file's tokens are
/// echoed clipped). Any other exception, or a message breaking the rule, aborts with what went wrong, which
/// libFuzzer reports as a crash with its input; crashes and sanitizer reports stop the process on their own.
/// @param source the file name the message must name
/// @param parse reads the input
/// @return whether `parse` succeeded (so the target can check a round trip)
bool refusedClearlyOrParsed(const std::string& source, const std::function<void()>& parse);

/// @brief Aborts with `what` when `condition` is false: a property of a parsed input that does not hold.
/// @param condition the property
/// @param what what does not hold, printed before aborting
void require(bool condition, const std::string& what);

}  // namespace weighted_icp::fuzz

/// libFuzzer's entry point, implemented by each target (fuzz_<name>.cpp).
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);
