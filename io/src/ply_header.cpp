// The strict PLY header reader (see ply_header.h).
#include "ply_header.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace weighted_icp::io::detail {

namespace {

/// A header is a few hundred bytes; a megabyte without end_header is not a PLY file.
constexpr std::uint64_t kMaxHeaderBytes = 1u << 20;

constexpr std::array<const char*, 16> kTypes = {"char",  "uchar",   "int8",   "uint8",  "short", "ushort",
                                                "int16", "uint16",  "int",    "uint",   "int32", "uint32",
                                                "float", "float32", "double", "float64"};

bool knownType(const std::string& type) {
  return std::any_of(kTypes.begin(), kTypes.end(), [&](const char* known) { return type == known; });
}

std::vector<std::string> words(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> out;
  for (std::string word; in >> word;) out.push_back(word);
  return out;
}

bool plainDigits(const std::string& word) {
  return !word.empty() && word.size() <= 19 &&
         std::all_of(word.begin(), word.end(), [](char c) { return c >= '0' && c <= '9'; });
}

/// "format ascii|binary_little_endian|binary_big_endian 1.0", split into words.
bool formatLine(const std::vector<std::string>& w) {
  return w.size() == 3 && w[0] == "format" &&
         (w[1] == "ascii" || w[1] == "binary_little_endian" || w[1] == "binary_big_endian") && w[2] == "1.0";
}

/// "property TYPE NAME" or "property list TYPE TYPE NAME" with types PLY knows, split into words.
bool propertyLine(const std::vector<std::string>& w) {
  const bool list = w.size() == 5 && w[1] == "list" && knownType(w[2]) && knownType(w[3]);
  return list || (w.size() == 3 && knownType(w[1]));
}

/// Why "element NAME COUNT" (split into words) is refused in a file of file_size bytes; empty when it is not.
std::string elementLineError(const std::vector<std::string>& w, std::uint64_t file_size) {
  if (w.size() != 3 || !plainDigits(w[2])) return "expected 'element NAME COUNT' with COUNT a number of 0 or more";
  if (std::stoull(w[2]) <= file_size) return {};
  return "the header declares more points than the file holds (" + w[2] +
         (w[1] == "vertex" ? " vertices" : " instances of element " + w[1].substr(0, 32)) + " in a file of " +
         std::to_string(file_size) + " bytes)";
}

}  // namespace

void requireWellFormedPlyHeader(std::istream& in, const std::string& path, std::uint64_t file_size) {
  std::size_t number = 0;
  const auto fail = [&](const std::string& what) {
    throw std::runtime_error(path + ": line " + std::to_string(number) + ": " + what);
  };
  std::string line;
  const auto next = [&] {
    if (!std::getline(in, line)) return false;
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const auto position = in.tellg();
    if (position != std::streampos(-1) && static_cast<std::uint64_t>(position) > kMaxHeaderBytes)
      fail("no end_header in the first " + std::to_string(kMaxHeaderBytes) + " bytes; not a PLY file");
    return true;
  };
  if (!next() || line != "ply") fail("the first line is not 'ply'; not a PLY file");
  if (!next()) fail("no format line");
  if (!formatLine(words(line))) fail("expected 'format ascii|binary_little_endian|binary_big_endian 1.0'");
  std::uint64_t instances = 0, count = 0, properties = 0;
  bool in_element = false;
  const auto closeElement = [&] {
    if (in_element && count > 0 && properties == 0) fail("an element with instances but no property");
  };
  while (next()) {
    const auto w = words(line);
    if (w.empty()) fail("an empty line in the header");
    // PCL's reader takes the keyword from the words but checks it at the line's start (an assertion, for obj_info).
    if (std::isspace(static_cast<unsigned char>(line[0])))
      fail("a header line starting with white space (a keyword starts its line)");
    if (w[0] == "comment" || w[0] == "obj_info") continue;
    if (w[0] == "end_header") {
      if (w.size() != 1) fail("end_header followed by more on its line");
      closeElement();
      if (instances > file_size)
        fail("the header declares more points than the file holds (" + std::to_string(instances) +
             " element instances in all in a file of " + std::to_string(file_size) + " bytes)");
      return;
    }
    if (w[0] == "element") {
      closeElement();
      if (const std::string why = elementLineError(w, file_size); !why.empty()) fail(why);
      count = std::stoull(w[2]);
      instances += count;
      properties = 0;
      in_element = true;
      continue;
    }
    if (w[0] == "property") {
      if (!in_element) fail("a property before any element");
      if (!propertyLine(w)) fail("expected 'property TYPE NAME' or 'property list TYPE TYPE NAME' with known types");
      ++properties;
      continue;
    }
    fail("unknown header keyword '" + w[0].substr(0, 32) +
         "' (expected comment, obj_info, element, property or end_header); not a PLY file");
  }
  fail("the header ends without end_header; not a PLY file");
}

}  // namespace weighted_icp::io::detail
