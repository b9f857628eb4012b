// The fuzz targets' shared helpers: scratch files, input splitting and the refusal rule.
#include "fuzz_support.h"

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <stdexcept>
#include <system_error>

#include <unistd.h>

namespace weighted_icp::fuzz {

namespace {
/// A message may quote a path and a few clipped tokens; anything longer echoes input it should have clipped.
constexpr std::size_t kMaxMessageBytes = 1024;

[[noreturn]] void fail(const std::string& what) {
  std::fprintf(stderr, "fuzz target: %s\n", what.c_str());
  std::fflush(stderr);
  std::abort();
}

void removeScratch() {
  std::error_code ignored;
  std::filesystem::remove_all(scratchFolder(), ignored);
}
}  // namespace

const std::filesystem::path& scratchFolder() {
  // Never destroyed: removeScratch runs at exit, and a static path would be destroyed before it (its destructor
  // is registered after the atexit call made while constructing it), leaving every folder behind.
  static const std::filesystem::path* const folder = [] {
    auto* path = new std::filesystem::path(std::filesystem::temp_directory_path() /
                                           ("weighted_icp_fuzz_" + std::to_string(::getpid())));
    std::filesystem::create_directories(*path);
    std::atexit(removeScratch);
    return path;
  }();
  return *folder;
}

std::string writeInput(const std::string& name, std::string_view bytes) {
  const auto path = scratchFolder() / name;
  std::filesystem::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  out.close();
  if (!out) fail("cannot write the input to " + path.string());
  return path.string();
}

std::vector<std::string_view> splitParts(std::string_view bytes, std::size_t parts) {
  static constexpr std::string_view kSeparator = "\n@@\n";
  std::vector<std::string_view> result;
  while (result.size() + 1 < parts) {
    const std::size_t at = bytes.find(kSeparator);
    if (at == std::string_view::npos) break;
    result.push_back(bytes.substr(0, at + 1));  // the part keeps its last newline
    bytes.remove_prefix(at + kSeparator.size());
  }
  result.push_back(bytes);
  return result;
}

bool refusedClearlyOrParsed(const std::string& source, const std::function<void()>& parse) {
  try {
    parse();
    return true;
  } catch (const std::runtime_error& e) {
    const std::string message = e.what();
    if (message.find(source) == std::string::npos) fail("the error does not name " + source + ": " + message);
    if (message.size() > kMaxMessageBytes + source.size())
      fail("an error of " + std::to_string(message.size()) + " bytes: " + message.substr(0, 200) + "...");
    return false;
  } catch (const std::exception& e) {
    fail(std::string("an exception other than std::runtime_error escaped: ") + e.what());
  }
}

void require(bool condition, const std::string& what) {
  if (!condition) fail(what);
}

}  // namespace weighted_icp::fuzz
