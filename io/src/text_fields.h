#pragma once
// The text formats io/ reads and writes: whitespace-separated fields of a
// line, and doubles written so that they read back exactly.

#include <cctype>
#include <charconv>
#include <string>
#include <string_view>
#include <vector>

namespace weighted_icp::io::detail {

inline std::vector<std::string_view> splitFields(std::string_view line) {
  std::vector<std::string_view> fields;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    const std::size_t start = i;
    while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    if (i > start) fields.push_back(line.substr(start, i - start));
  }
  return fields;
}

/// Shortest text that reads back to the same double.
inline std::string exact(double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, result.ptr);
}

}  // namespace weighted_icp::io::detail
