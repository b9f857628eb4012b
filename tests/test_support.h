#pragma once
// Shared by the tests: where the real data is, and skipping when it is absent.

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

namespace weighted_icp::testing {

inline std::filesystem::path dataDir() { return WEIGHTED_ICP_DATA_DIR; }
inline std::filesystem::path realMapPath() { return dataDir() / "map_fr1_desk.txt"; }
inline std::filesystem::path binaryDir() { return WEIGHTED_ICP_BINARY_DIR; }

/// A fresh, empty folder for one test's files.
inline std::filesystem::path scratchDir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("weighted_icp_test_" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

/// The bytes of a file, or "" when it cannot be read.
inline std::string readFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

inline void writeFile(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

}  // namespace weighted_icp::testing

/// Skips the test, saying why, only where the shared data set is absent.
#define WEIGHTED_ICP_REQUIRE_FILE(path)                                                   \
  do {                                                                                    \
    if (!std::filesystem::exists(path))                                                   \
      GTEST_SKIP() << "needs " << (path) << " (the shared data set beside the project); " \
                   << "configure with -DWEIGHTED_ICP_DATA_DIR=... to point elsewhere";    \
  } while (0)
