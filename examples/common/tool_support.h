#pragma once
// What every command-line tool of weighted_icp shares: the way it reports
// errors, progress on long runs, JSON output and safe file writing.

#include <chrono>
#include <cstddef>
#include <functional>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <boost/program_options.hpp>

namespace weighted_icp::tools {

/// Runs a tool's body: prints "<tool>: error: <what>" to stderr and returns 1
/// on any exception, 2 on a command-line error (boost::program_options).
int runTool(const std::string& tool, const std::function<int()>& body);

/// Parses argv against `options` (which declare "help,h"), with optional
/// positional arguments. Returns false, having printed the options, when
/// --help is given; throws boost::program_options::error on a bad command line.
bool parseCommandLine(int argc, const char* const argv[], const boost::program_options::options_description& options,
                      boost::program_options::variables_map& vm,
                      const boost::program_options::positional_options_description* positional = nullptr);

/// One line on stderr, rewritten in place: "label  12/40  (30%)  eta 5 s".
/// Prints plain lines instead when stderr is not a terminal (CI logs).
class Progress {
 public:
  Progress(std::string label, std::size_t total);
  void step(const std::string& detail = {});
  void finish();

 private:
  std::string label_;
  std::size_t total_;
  std::size_t done_ = 0;
  bool terminal_;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_print_;
};

/// A flat JSON object written in insertion order; values are numbers, bools,
/// strings or matrices (as arrays of rows).
class JsonObject {
 public:
  JsonObject& add(const std::string& key, double value);
  JsonObject& add(const std::string& key, int value);
  JsonObject& add(const std::string& key, std::size_t value);
  JsonObject& add(const std::string& key, bool value);
  JsonObject& add(const std::string& key, const std::string& value);
  JsonObject& add(const std::string& key, const char* value) { return add(key, std::string(value)); }
  JsonObject& add(const std::string& key, const Eigen::MatrixXd& value);
  /// Single line, no trailing newline.
  std::string str() const;

 private:
  std::vector<std::pair<std::string, std::string>> members_;
};

/// Writes a text file atomically (temporary file, then rename).
void writeTextFile(const std::string& path, const std::string& content);

}  // namespace weighted_icp::tools
