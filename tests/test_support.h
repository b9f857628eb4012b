#pragma once
// Shared by the tests: where the real data is, skipping when it is absent, and each test's own scratch folder.

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <system_error>

#include <unistd.h>

#include <gtest/gtest.h>

namespace weighted_icp::testing {

inline std::filesystem::path dataDir() { return WEIGHTED_ICP_DATA_DIR; }
inline std::filesystem::path realMapPath() { return dataDir() / "map_fr1_desk.txt"; }
/// The TUM head of Freiburg 1 (tum_fr1_xyz_head) or, for any other number, 3 (tum_fr3_teddy_head).
inline std::filesystem::path tumHeadDir(int freiburg) {
  return dataDir() / (freiburg == 1 ? "tum_fr1_xyz_head" : "tum_fr3_teddy_head");
}
inline std::filesystem::path binaryDir() { return WEIGHTED_ICP_BINARY_DIR; }
inline std::filesystem::path sourceDir() { return WEIGHTED_ICP_SOURCE_DIR; }
/// The Python the project's scripts run with (Debian's, with numpy).
inline std::filesystem::path pythonPath() { return WEIGHTED_ICP_PYTHON; }

/// Where this test process keeps its scratch folders. The process id makes it this run's own: ctest -j runs
/// every test in its own process, side by side with other runs (another worktree, another user).
inline std::filesystem::path scratchRoot() {
  return std::filesystem::temp_directory_path() / ("weighted_icp_tests_" + std::to_string(::getpid()));
}

/// "Suite.Test" as a folder name ('/' of parameterised names replaced), or "outside_tests" outside a test.
inline std::string testFolderName(const ::testing::TestInfo* test) {
  if (!test) return "outside_tests";
  std::string name = std::string(test->test_suite_name()) + "." + test->name();
  for (char& c : name)
    if (c == '/') c = '_';
  return name;
}

/// A fresh, empty folder for one test's files: <scratchRoot>/<Suite.Test>/<name>. It belongs to the running
/// test alone, so tests that pick the same `name` never remove or read each other's files, even in parallel.
/// @param name  distinguishes the folders one test asks for (a test may want several)
inline std::filesystem::path scratchDir(const std::string& name) {
  const auto dir = scratchRoot() / testFolderName(::testing::UnitTest::GetInstance()->current_test_info()) / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

/// Removes a test's scratch folder once it has not failed (a failed test's files stay for inspection),
/// and the process's root at the end when nothing is left in it, so per-process folders do not pile up.
class ScratchCleaner : public ::testing::EmptyTestEventListener {
  void OnTestEnd(const ::testing::TestInfo& test) override {
    std::error_code ignored;
    if (!test.result()->Failed()) std::filesystem::remove_all(scratchRoot() / testFolderName(&test), ignored);
  }
  void OnTestProgramEnd(const ::testing::UnitTest&) override {
    std::error_code ignored;
    std::filesystem::remove(scratchRoot(), ignored);  // only removes an empty folder
  }
};

/// Installs the cleaner once per test program, before gtest's main runs (the listeners list owns it).
inline const bool kScratchCleanerInstalled = [] {
  ::testing::UnitTest::GetInstance()->listeners().Append(new ScratchCleaner);
  return true;
}();

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

/// True when `path` starts with the PNG signature (a tool's picture).
inline bool isPng(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  char magic[8] = {};
  in.read(magic, 8);
  return in && std::string(magic + 1, 3) == "PNG";
}

}  // namespace weighted_icp::testing

/// Skips the test, saying why, only where the shared data set is absent.
#define WEIGHTED_ICP_REQUIRE_FILE(path)                                                   \
  do {                                                                                    \
    if (!std::filesystem::exists(path))                                                   \
      GTEST_SKIP() << "needs " << (path) << " (the shared data set beside the project); " \
                   << "configure with -DWEIGHTED_ICP_DATA_DIR=... to point elsewhere";    \
  } while (0)
