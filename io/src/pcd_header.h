// A strict reader of PCD headers (private to io): PCL's own reader allocates what a header declares before it
// reads any data, so every PCD header is checked here first, and only a well-formed one reaches PCL.
#pragma once

#include <cstdint>
#include <istream>
#include <optional>
#include <string>
#include <vector>

namespace weighted_icp::io::detail {

/// @brief The header of a PCD file as the format documents it (PCD v0.7; VERSION, VIEWPOINT, COUNT and HEIGHT may be
/// absent, as in older files).
///
/// Only a header PCL reads exactly as written is accepted: every keyword spelled in full, at most once, FIELDS
/// before SIZE, TYPE and COUNT, one value per field in each, SIZE 1, 2, 4 or 8, TYPE I, U or F, POINTS equal to
/// WIDTH x HEIGHT. PCL itself matches keywords by prefix, lets the last of a repeated keyword win and allocates at
/// each POINTS line; five fuzzed headers used one such leniency each to make it allocate gigabytes
/// (fuzz/regressions/cloud_pcd/). A whitelist ends that class of input instead of answering each one.
struct PcdHeader {
  /// @brief How the point data is stored after the DATA line.
  enum class Data { ascii, binary, binary_compressed };

  std::vector<std::string> names;     ///< FIELDS
  std::vector<std::uint64_t> sizes;   ///< SIZE: bytes of one value of each field
  std::vector<char> types;            ///< TYPE: I, U or F
  std::vector<std::uint64_t> counts;  ///< COUNT: values per field (1 where the header has no COUNT)
  std::uint64_t width = 0;            ///< WIDTH
  std::uint64_t height = 1;           ///< HEIGHT (1 where absent)
  std::uint64_t points = 0;           ///< POINTS, which must be WIDTH x HEIGHT
  Data data = Data::ascii;            ///< DATA
  std::uint64_t data_offset = 0;      ///< the first byte after the DATA line

  /// @brief Bytes of one point: the sum of SIZE x COUNT.
  std::uint64_t pointBytes() const;
  /// @brief Values of one point: the sum of COUNT.
  std::uint64_t pointValues() const;
};

/// @brief What PCL's header reader would take as more header after the DATA line, if anything. PCL does not stop
/// at DATA: it reads on, skipping empty lines and those starting with '#', and takes any line whose first word
/// begins with a keyword (or COLUMNS, its old FIELDS) as header, until a line that does not.
/// @param in the file, positioned just after its DATA line
/// @return that line's first word (clipped to 32 bytes), or nothing when PCL would stop at the data
std::optional<std::string> dataPclReadsAsHeader(std::istream& in);

/// @brief Reads and checks a PCD header from the start of `in` to its DATA line only, leaving `in` just after it.
/// @param in   the file, opened in binary mode, at its first byte
/// @param path the file's name, for messages
/// @throws std::runtime_error "<path>: line <n>: <what is wrong>" for anything but a well-formed header
PcdHeader readPcdHeaderToData(std::istream& in, const std::string& path);

/// @brief Reads and checks a PCD header, from the start of `in` to its DATA line, and the data after it as far as
/// PCL's header reader would look (dataPclReadsAsHeader: data it would read as more header is refused).
/// @param in   the file, opened in binary mode, at its first byte
/// @param path the file's name, for messages
/// @throws std::runtime_error "<path>: line <n>: <what is wrong>" for anything but a well-formed header
PcdHeader readPcdHeader(std::istream& in, const std::string& path);

/// @brief Checks that the file holds the data its header declares, so that nothing PCL allocates from the header
/// exceeds a small multiple of the file's size: binary data holds every point's bytes; ASCII data holds at least one
/// byte per value; LZF-compressed data's own sizes must agree with the header and with the file, and LZF expands at
/// most about 90 times (a 3-byte back-reference copies at most 264 bytes), taken as 100.
/// @param in     the same stream readPcdHeader read
/// @param header what readPcdHeader returned
/// @param path   the file's name, for messages
/// @throws std::runtime_error naming the file and the declared and available sizes
void requirePcdDataFitsFile(std::istream& in, const PcdHeader& header, const std::string& path);

}  // namespace weighted_icp::io::detail
