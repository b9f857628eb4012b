#pragma once
// Writing files so that a failure never leaves a half-written output: write to
// a temporary file in the same folder, then rename it over the target.

#include <filesystem>
#include <functional>
#include <string>

namespace weighted_icp::io {

/// @brief Calls `write(temporary_path)`, flushes the temporary file to the disk
/// (syncToDisk), then renames it to `path`. On any exception the temporary file
/// is removed and `path` is untouched.
/// @param path the file to create or replace
/// @param write writes the whole content to the path it is given; throws on failure
void writeAtomically(const std::string& path, const std::function<void(const std::string&)>& write);

/// @brief Flushes a written file (or folder) to the disk, so that a rename
/// publishing it cannot outlive its contents after a crash, and so that
/// delayed write errors (a full disk) are seen now; throws std::runtime_error.
/// @param path the file or folder to flush
void syncToDisk(const std::filesystem::path& path);

}  // namespace weighted_icp::io
