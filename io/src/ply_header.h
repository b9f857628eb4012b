// A strict reader of PLY headers (private to io): PCL's PLY parser reads every element a header declares, as many
// times as it declares, so every PLY header is checked here first, and only a well-formed one reaches PCL.
#pragma once

#include <cstdint>
#include <istream>
#include <string>

namespace weighted_icp::io::detail {

/// @brief Checks a PLY header from the start of `in` to its end_header line: "ply", a format line (ascii,
/// binary_little_endian or binary_big_endian, version 1.0), then only comment, obj_info, element and property lines.
/// Every element has a name and a count of plain digits (PCL reads "-3" as 2^64 - 3 and loops that often: a
/// 453-byte fuzzed file hung it), at least one property when its count is not zero (PCL loops over instances that
/// read nothing), and properties of known types (or lists of them). Each instance takes at least one byte, so the
/// counts together may not exceed the file's size.
/// @param in        the file, opened in binary mode, at its first byte
/// @param path      the file's name, for messages
/// @param file_size the file's size in bytes
/// @throws std::runtime_error "<path>: line <n>: <what is wrong>"
void requireWellFormedPlyHeader(std::istream& in, const std::string& path, std::uint64_t file_size);

}  // namespace weighted_icp::io::detail
