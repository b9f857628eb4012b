#pragma once
// The landmark map format of the mini-map alignment paper, one record a line,
// whitespace separated:
//
//   FRAME id tx ty tz qw qx qy qz
//     camera-to-world pose; the quaternion is scalar FIRST (unlike TUM
//     ground truth, which is x y z w).
//   LANDMARK id x y z c00 c01 c02 c10 c11 c12 c20 c21 c22 n  (frame u v) x n
//     world position, row-major 3x3 position covariance, then n observations.
//
// Blank lines and lines starting with '#' are skipped.

#include <istream>
#include <stdexcept>
#include <string>

#include "weighted_icp/registration/landmark_map.h"

namespace weighted_icp::io {

/// A malformed map: what() names the file, the line and what is wrong.
class MapFormatError : public std::runtime_error {
 public:
  MapFormatError(const std::string& source, std::size_t line, const std::string& what);
  const std::string& source() const { return source_; }
  std::size_t line() const { return line_; }

 private:
  std::string source_;
  std::size_t line_;
};

/// Reads a map; `source` names the stream in errors. Every observation must
/// refer to a FRAME of the map; ids must be unique.
LandmarkMap parseLandmarkMap(std::istream& in, const std::string& source);
/// Throws MapFormatError (also when the file cannot be opened).
LandmarkMap readLandmarkMap(const std::string& path);

/// Writes frames then landmarks with round-trip precision. Writes to a
/// temporary file beside `path` and renames it, so a failure leaves any
/// existing file intact. Throws std::runtime_error naming the path.
void writeLandmarkMap(const LandmarkMap& map, const std::string& path);
void writeLandmarkMap(const LandmarkMap& map, std::ostream& out);

}  // namespace weighted_icp::io
