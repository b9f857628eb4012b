#pragma once
// Writing files so that a failure never leaves a half-written output: write to
// a temporary file in the same folder, then rename it over the target.

#include <functional>
#include <string>

namespace weighted_icp::io {

/// Calls `write(temporary_path)`, then renames the temporary file to `path`.
/// On any exception the temporary file is removed and `path` is untouched.
void writeAtomically(const std::string& path, const std::function<void(const std::string&)>& write);

}  // namespace weighted_icp::io
