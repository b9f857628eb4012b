#pragma once
// The text formats io/ reads and writes: whitespace-separated fields of a
// line, and doubles written so that they read back exactly.

#include <cctype>
#include <charconv>
#include <cstdio>
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

/// Bytes of a token an error message shows: enough to recognise it.
constexpr std::size_t kMaxEchoedBytes = 40;

/// @brief A token read from a file, fit to be echoed in an error message.
/// A file can hold anything: a NUL would cut the message short, binary bytes
/// would reach the terminal raw, and a 1 MB token would be printed in full.
/// So non-printable bytes become \xNN and only the first kMaxEchoedBytes are kept;
/// a cut token ends with "… (N bytes)" so the reader knows it was cut.
/// @param text the token as read.
/// @return the token without quotes (for a value that reads as a number).
inline std::string clipToken(std::string_view text) {
  std::string out;
  const std::size_t kept = text.size() < kMaxEchoedBytes ? text.size() : kMaxEchoedBytes;
  for (std::size_t i = 0; i < kept; ++i) {
    const auto byte = static_cast<unsigned char>(text[i]);
    if (byte == '\\' || !std::isprint(byte)) {
      char escaped[5];
      std::snprintf(escaped, sizeof(escaped), "\\x%02x", static_cast<unsigned>(byte));
      out += escaped;
    } else {
      out += static_cast<char>(byte);
    }
  }
  if (kept < text.size()) out += "\u2026 (" + std::to_string(text.size()) + " bytes)";
  return out;
}

/// @brief clipToken() in single quotes, the cut mark after the closing quote.
/// @param text the token as read.
inline std::string quoteToken(std::string_view text) {
  if (text.size() <= kMaxEchoedBytes) return "'" + clipToken(text) + "'";
  return "'" + clipToken(text.substr(0, kMaxEchoedBytes)) + "'\u2026 (" + std::to_string(text.size()) + " bytes)";
}

}  // namespace weighted_icp::io::detail
