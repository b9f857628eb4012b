#pragma once
// Runs a built command-line tool as a user would, for the tests that check
// exit codes, stdout and stderr.

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <string>

#include <Eigen/Core>

#include "test_support.h"

namespace weighted_icp::testing {

/// What a tool run gave: its exit status (128 + the signal when killed by one), stdout and stderr.
struct ToolRun {
  int status = -1;
  std::string out;
  std::string err;
};

/// Runs `program_and_args` (shell syntax). stderr goes through a file in `scratch`, removed afterwards. With
/// `timeout_seconds` > 0 the run is killed after that long (status 124), so an option that makes a tool run
/// forever fails the test instead of hanging it.
inline ToolRun runCommand(const std::string& program_and_args, const std::filesystem::path& scratch,
                          int timeout_seconds = 0) {
  const std::filesystem::path err_file = scratch / "stderr.txt";
  const std::string limit = timeout_seconds > 0 ? "timeout " + std::to_string(timeout_seconds) + " " : "";
  const std::string command = limit + program_and_args + " 2>'" + err_file.string() + "'";
  ToolRun result;
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) {
    result.err = "cannot run " + command;
    return result;
  }
  std::array<char, 4096> buffer{};  // fread, not fgets: a NUL byte in the output must not cut it
  for (std::size_t n; (n = std::fread(buffer.data(), 1, buffer.size(), pipe)) > 0;) result.out.append(buffer.data(), n);
  // A tool killed by a signal reports 128 + the signal, as a shell does: WEXITSTATUS alone would read 0.
  const int status = pclose(pipe);
  result.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
  {
    std::ifstream err(err_file);
    result.err.assign(std::istreambuf_iterator<char>(err), {});
  }
  // The scratch folder then holds only what the tool wrote.
  std::error_code ignored;
  std::filesystem::remove(err_file, ignored);
  return result;
}

/// Runs build/examples/<tool> with `args` (shell syntax), as runCommand.
inline ToolRun runBuiltTool(const std::string& tool, const std::string& args, const std::filesystem::path& scratch,
                            int timeout_seconds = 0) {
  return runCommand("'" + (binaryDir() / "examples" / tool).string() + "' " + args, scratch, timeout_seconds);
}

/// Runs scripts/<script> with the project's Python (pythonPath()) and `args`, as runCommand.
inline ToolRun runScript(const std::string& script, const std::string& args, const std::filesystem::path& scratch) {
  return runCommand("'" + pythonPath().string() + "' '" + (sourceDir() / "scripts" / script).string() + "' " + args,
                    scratch);
}

/// The last non-empty line of a tool's output: where --json puts its object.
inline std::string lastLine(const std::string& text) {
  std::istringstream in(text);
  std::string line, last;
  while (std::getline(in, line))
    if (!line.empty()) last = line;
  return last;
}

/// The `transformation` of wicp_align's JSON object (4 rows of 4 numbers).
inline Eigen::Matrix4d alignTransformation(const std::string& json) {
  const std::regex number("-?[0-9.]+(e[-+]?[0-9]+)?");
  const std::string rows = json.substr(json.find("[["), json.find("]]") - json.find("[[") + 2);
  Eigen::Matrix4d t;
  auto it = std::sregex_iterator(rows.begin(), rows.end(), number);
  for (int i = 0; i < 16; ++i, ++it) t(i / 4, i % 4) = std::stod(it->str());
  return t;
}

/// The number `key` holds in a flat JSON object (a tool's report); std::runtime_error when it holds none.
inline double jsonNumber(const std::string& json, const std::string& key) {
  std::smatch match;
  if (!std::regex_search(json, match, std::regex("\"" + key + "\":\\s*(-?[0-9.eE+-]+)")))
    throw std::runtime_error("no number " + key + " in " + json);
  return std::stod(match[1]);
}

}  // namespace weighted_icp::testing
