#pragma once
// The mapping layer's text formats (session folder, mini-map graph): records of
// whitespace-separated fields, one a line, read with errors that name the file
// and the line (io::MapFormatError), written with round-trip precision.

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Geometry>

#include "weighted_icp/io/map_format.h"

namespace weighted_icp::mapping::detail {

/// Shortest text that reads back to the same double.
inline std::string exact(double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, result.ptr);
}

/// "tx ty tz qw qx qy qz" of a pose (scalar-first quaternion, as the paper's map format).
inline std::string poseFields(const Eigen::Isometry3d& pose) {
  const Eigen::Quaterniond q(pose.linear());
  std::string out;
  for (const double value :
       {pose.translation().x(), pose.translation().y(), pose.translation().z(), q.w(), q.x(), q.y(), q.z()})
    out += (out.empty() ? "" : " ") + exact(value);
  return out;
}

/// A token fit for an error message: printable, at most 40 bytes.
inline std::string echo(std::string_view text) {
  std::string out;
  for (std::size_t i = 0; i < text.size() && i < 40; ++i)
    out += std::isprint(static_cast<unsigned char>(text[i])) ? text[i] : '?';
  if (text.size() > 40) out += "... (" + std::to_string(text.size()) + " bytes)";
  return "'" + out + "'";
}

/// Reads a file record by record: blank lines and '#' comments are skipped.
class RecordReader {
 public:
  /// Opens `path`; throws io::MapFormatError naming it if it cannot be read.
  explicit RecordReader(std::string path) : path_(std::move(path)), in_(path_) {
    if (!in_) throw io::MapFormatError(path_, 0, "cannot open the file");
  }

  /// The next record, false at the end of the file.
  bool next() {
    while (std::getline(in_, text_)) {
      ++line_;
      fields_.clear();
      std::size_t i = 0;
      while (i < text_.size()) {
        while (i < text_.size() && std::isspace(static_cast<unsigned char>(text_[i]))) ++i;
        const std::size_t start = i;
        while (i < text_.size() && !std::isspace(static_cast<unsigned char>(text_[i]))) ++i;
        if (i > start) fields_.emplace_back(text_.data() + start, i - start);
      }
      if (!fields_.empty() && fields_[0][0] != '#') return true;
    }
    if (in_.bad()) fail("read error");
    fields_.clear();
    return false;
  }
  /// The next record, which must exist and start with `keyword`.
  void expect(const std::string& keyword) {
    if (!next()) {
      ++line_;
      fail("the file ends where a " + keyword + " record was expected");
    }
    if (fields_[0] != keyword) fail("expected a " + keyword + " record, found " + echo(fields_[0]));
  }
  /// Fails unless the record has exactly `count` fields (keyword included).
  void expectFields(std::size_t count) const {
    if (fields_.size() != count)
      fail(echo(fields_[0]) + " record has " + std::to_string(fields_.size()) + " fields, expected " +
           std::to_string(count));
  }
  /// Fails unless the record has at least `count` fields.
  void expectAtLeast(std::size_t count) const {
    if (fields_.size() < count)
      fail(echo(fields_[0]) + " record has " + std::to_string(fields_.size()) + " fields, expected at least " +
           std::to_string(count));
  }

  std::size_t size() const { return fields_.size(); }
  /// Field i; a record too short for it fails (naming the file and line) rather than throwing std::out_of_range.
  std::string_view field(std::size_t i) const {
    if (i >= fields_.size())
      fail((fields_.empty() ? std::string("the record") : std::string(echo(fields_[0])) + " record") + " has " +
           std::to_string(fields_.size()) + " fields, field " + std::to_string(i + 1) + " is missing");
    return fields_[i];
  }
  std::size_t line() const { return line_; }
  const std::string& path() const { return path_; }

  /// Field i as a finite double.
  double number(std::size_t i, const std::string& name) const {
    double value = 0.0;
    const std::string_view text = field(i);
    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (error != std::errc() || end != text.data() + text.size()) fail(name + " " + echo(text) + " is not a number");
    if (!std::isfinite(value)) fail(name + " must be finite");
    return value;
  }
  /// Field i as a non-negative integer.
  std::uint64_t count(std::size_t i, const std::string& name) const {
    std::uint64_t value = 0;
    const std::string_view text = field(i);
    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (error != std::errc() || end != text.data() + text.size())
      fail(name + " " + echo(text) + " is not a non-negative integer");
    return value;
  }
  /// Field i as an int (may be negative).
  int integer(std::size_t i, const std::string& name) const {
    int value = 0;
    const std::string_view text = field(i);
    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (error != std::errc() || end != text.data() + text.size()) fail(name + " " + echo(text) + " is not an integer");
    return value;
  }
  /// Fields i..i+6 as a pose (tx ty tz qw qx qy qz); the quaternion must be near unit length.
  Eigen::Isometry3d pose(std::size_t i) const {
    const Eigen::Vector3d t(number(i, "tx"), number(i + 1, "ty"), number(i + 2, "tz"));
    const Eigen::Quaterniond q(number(i + 3, "qw"), number(i + 4, "qx"), number(i + 5, "qy"), number(i + 6, "qz"));
    if (std::abs(q.norm() - 1.0) > 1e-3) fail("the quaternion is not of unit length (" + exact(q.norm()) + ")");
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = q.normalized().toRotationMatrix();
    pose.translation() = t;
    return pose;
  }
  /// Throws io::MapFormatError naming the file and the current line.
  [[noreturn]] void fail(const std::string& what) const { throw io::MapFormatError(path_, line_, what); }

 private:
  std::string path_;
  std::ifstream in_;
  std::string text_;
  std::vector<std::string_view> fields_;
  std::size_t line_ = 0;
};

/// Lower-case hex of `size` bytes.
inline std::string toHex(const unsigned char* bytes, std::size_t size) {
  static const char digits[] = "0123456789abcdef";
  std::string out(2 * size, '0');
  for (std::size_t i = 0; i < size; ++i) {
    out[2 * i] = digits[bytes[i] >> 4];
    out[2 * i + 1] = digits[bytes[i] & 15];
  }
  return out;
}

/// Decodes hex into `out` (its size fixes how many bytes); false on a wrong length or a non-hex digit.
inline bool fromHex(std::string_view text, unsigned char* out, std::size_t size) {
  if (text.size() != 2 * size) return false;
  const auto digit = [](char c) -> int {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
  };
  for (std::size_t i = 0; i < size; ++i) {
    const int high = digit(text[2 * i]), low = digit(text[2 * i + 1]);
    if (high < 0 || low < 0) return false;
    out[i] = static_cast<unsigned char>(high * 16 + low);
  }
  return true;
}

}  // namespace weighted_icp::mapping::detail
