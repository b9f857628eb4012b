// A strict reader of PCD headers: a whitelist of what the format documents, so that PCL only sees headers it reads
// exactly as written, and never allocates more than a small multiple of the file's size.
#include "pcd_header.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <system_error>

namespace weighted_icp::io::detail {

namespace {

constexpr std::uint64_t kLargest = std::numeric_limits<std::uint64_t>::max();
/// A header is a few hundred bytes; a megabyte without a DATA line is not a PCD file.
constexpr std::uint64_t kMaxHeaderBytes = 1u << 20;
/// Generous bounds that no real cloud reaches and that keep every product below in range.
constexpr std::uint64_t kMaxFields = 4096;
constexpr std::uint64_t kMaxCount = 1u << 20;
/// PCL indexes points with 32-bit integers.
constexpr std::uint64_t kMaxPoints = std::numeric_limits<std::int32_t>::max();
/// LZF expands at most about 90 times; see requirePcdDataFitsFile.
constexpr std::uint64_t kLzfMaxExpansion = 100;

std::uint64_t saturatingProduct(std::uint64_t a, std::uint64_t b) {
  return b != 0 && a > kLargest / b ? kLargest : a * b;
}

/// The lines of a header, with the number of the line being read, for messages.
class HeaderLines {
 public:
  HeaderLines(std::istream& in, std::string path) : in_(in), path_(std::move(path)) {}

  /// The next line without its newline; false at the end of the file.
  bool next(std::string& line) {
    if (!std::getline(in_, line)) return false;
    ++number_;
    const auto position = in_.tellg();
    if (position != std::streampos(-1) && static_cast<std::uint64_t>(position) > kMaxHeaderBytes)
      fail("no DATA line in the first " + std::to_string(kMaxHeaderBytes) + " bytes; not a PCD file");
    return true;
  }

  [[noreturn]] void fail(const std::string& what) const {
    throw std::runtime_error(path_ + ": line " + std::to_string(number_) + ": " + what);
  }

  std::size_t number() const { return number_; }

 private:
  std::istream& in_;
  std::string path_;
  std::size_t number_ = 0;
};

/// Splits a line at spaces and tabs (a trailing carriage return is a separator too, as PCL takes it).
std::vector<std::string> tokens(const std::string& line) {
  std::vector<std::string> out;
  std::string current;
  for (const char c : line) {
    if (c == ' ' || c == '\t' || c == '\r') {
      if (!current.empty()) out.push_back(std::move(current));
      current.clear();
    } else {
      current.push_back(c);
    }
  }
  if (!current.empty()) out.push_back(std::move(current));
  return out;
}

/// Printable ASCII, spaces and tabs only: PCL and the standard library split at different control characters.
bool printable(const std::string& line) {
  return std::all_of(line.begin(), line.end(), [](char c) {
    const auto u = static_cast<unsigned char>(c);
    return (u >= 0x20 && u < 0x7f) || c == '\t' || c == '\r';
  });
}

std::optional<std::uint64_t> unsignedNumber(const std::string& token) {
  if (token.empty() || token.size() > 19 ||
      !std::all_of(token.begin(), token.end(), [](char c) { return c >= '0' && c <= '9'; }))
    return std::nullopt;
  std::uint64_t value = 0;
  std::from_chars(token.data(), token.data() + token.size(), value);
  return value;
}

/// What has been read so far, and which keywords.
struct Reading {
  PcdHeader header;
  std::array<bool, 9> seen{};  // indexed by Keyword
  std::optional<std::uint64_t> points;
};

enum Keyword { kVersion, kFields, kSize, kType, kCount, kWidth, kHeight, kViewpoint, kPoints };
constexpr std::array<const char*, 9> kKeywords = {"VERSION", "FIELDS", "SIZE",      "TYPE",  "COUNT",
                                                  "WIDTH",   "HEIGHT", "VIEWPOINT", "POINTS"};

/// One value per field: SIZE, TYPE or COUNT.
std::vector<std::string> perFieldValues(const std::vector<std::string>& words, const Reading& reading,
                                        const HeaderLines& lines) {
  if (!reading.seen[kFields]) lines.fail(words[0] + " before FIELDS");
  if (words.size() - 1 != reading.header.names.size())
    lines.fail(words[0] + " has " + std::to_string(words.size() - 1) + " values for " +
               std::to_string(reading.header.names.size()) + " fields");
  return {words.begin() + 1, words.end()};
}

std::uint64_t singleNumber(const std::vector<std::string>& words, std::uint64_t largest, const HeaderLines& lines) {
  const auto value = words.size() == 2 ? unsignedNumber(words[1]) : std::nullopt;
  if (!value)
    lines.fail(words[0] + " must be a number of points (one non-negative integer), not '" +
               (words.size() > 1 ? words[1].substr(0, 32) : std::string()) + "'");
  if (*value > largest) lines.fail(words[0] + " " + words[1] + " is larger than " + std::to_string(largest));
  return *value;
}

void readFieldLine(Keyword keyword, const std::vector<std::string>& words, Reading& reading, const HeaderLines& lines) {
  PcdHeader& h = reading.header;
  switch (keyword) {
    case kFields:
      if (words.size() < 2 || words.size() - 1 > kMaxFields)
        lines.fail("FIELDS must name between 1 and " + std::to_string(kMaxFields) + " fields");
      h.names.assign(words.begin() + 1, words.end());
      h.counts.assign(h.names.size(), 1);
      break;
    case kSize:
      for (const auto& value : perFieldValues(words, reading, lines)) {
        const auto size = unsignedNumber(value);
        if (!size || (*size != 1 && *size != 2 && *size != 4 && *size != 8))
          lines.fail("SIZE '" + value + "' is not 1, 2, 4 or 8");
        h.sizes.push_back(*size);
      }
      break;
    case kType:
      for (const auto& value : perFieldValues(words, reading, lines)) {
        if (value != "I" && value != "U" && value != "F") lines.fail("TYPE '" + value + "' is not I, U or F");
        h.types.push_back(value[0]);
      }
      break;
    case kCount:
      h.counts.clear();
      for (const auto& value : perFieldValues(words, reading, lines)) {
        const auto count = unsignedNumber(value);
        if (!count || *count == 0 || *count > kMaxCount)
          lines.fail("COUNT '" + value + "' is not between 1 and " + std::to_string(kMaxCount));
        h.counts.push_back(*count);
      }
      break;
    default: break;
  }
}

void readKeywordLine(Keyword keyword, const std::vector<std::string>& words, Reading& reading,
                     const HeaderLines& lines) {
  switch (keyword) {
    case kVersion:
      if (words.size() != 2) lines.fail("VERSION must be followed by one version");
      break;
    case kWidth: reading.header.width = singleNumber(words, kMaxPoints, lines); break;
    case kHeight: reading.header.height = singleNumber(words, kMaxPoints, lines); break;
    case kPoints: reading.points = singleNumber(words, kMaxPoints, lines); break;
    case kViewpoint:
      if (words.size() != 8) lines.fail("VIEWPOINT must be followed by 7 numbers (tx ty tz qw qx qy qz)");
      for (std::size_t i = 1; i < words.size(); ++i) {
        std::istringstream number(words[i]);
        number.imbue(std::locale::classic());
        double value = 0.0;
        if (!(number >> value) || !number.eof() || !std::isfinite(value))
          lines.fail("VIEWPOINT value '" + words[i] + "' is not a finite number");
      }
      break;
    default: readFieldLine(keyword, words, reading, lines);
  }
}

PcdHeader::Data dataKind(const std::vector<std::string>& words, const HeaderLines& lines) {
  if (words.size() == 2 && words[1] == "ascii") return PcdHeader::Data::ascii;
  if (words.size() == 2 && words[1] == "binary") return PcdHeader::Data::binary;
  if (words.size() == 2 && words[1] == "binary_compressed") return PcdHeader::Data::binary_compressed;
  lines.fail("DATA must be followed by ascii, binary or binary_compressed");
}

/// The header is complete and its parts agree.
void requireComplete(Reading& reading, const HeaderLines& lines) {
  PcdHeader& h = reading.header;
  for (const Keyword required : {kFields, kSize, kType, kWidth, kPoints})
    if (!reading.seen[required]) lines.fail(std::string("the header has no ") + kKeywords[required] + " line");
  const std::uint64_t organised = saturatingProduct(h.width, h.height);
  if (organised > kMaxPoints) lines.fail("WIDTH x HEIGHT is larger than " + std::to_string(kMaxPoints));
  if (*reading.points != organised)
    lines.fail("POINTS " + std::to_string(*reading.points) + " is not WIDTH x HEIGHT (" + std::to_string(h.width) +
               " x " + std::to_string(h.height) + ")");
  h.points = organised;
}

}  // namespace

std::uint64_t PcdHeader::pointBytes() const {
  std::uint64_t bytes = 0;
  for (std::size_t i = 0; i < sizes.size() && i < counts.size(); ++i) bytes += sizes[i] * counts[i];
  return bytes;
}

std::uint64_t PcdHeader::pointValues() const {
  std::uint64_t values = 0;
  for (const auto count : counts) values += count;
  return values;
}

std::optional<std::string> dataPclReadsAsHeader(std::istream& in) {
  static constexpr std::array<const char*, 11> kPclPrefixes = {
      "VERSION", "FIELDS", "COLUMNS", "SIZE", "TYPE", "COUNT", "WIDTH", "HEIGHT", "VIEWPOINT", "POINTS", "DATA"};
  // Whitespace as PCL's tokenizer takes it (the classic locale's).
  const auto space = [](char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\v' || c == '\f' || c == '\r'; };
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    const auto begin = std::find_if_not(line.begin(), line.end(), space);
    const std::string first(begin, std::find_if(begin, line.end(), space));
    if (!first.empty() && first[0] == '#') continue;  // a comment to PCL: it reads on
    for (const char* prefix : kPclPrefixes)
      if (first.rfind(prefix, 0) == 0) return first.substr(0, 32);
    return std::nullopt;  // PCL stops here
  }
  return std::nullopt;
}

namespace {
/// Refuses data PCL's header reader would read as more header (dataPclReadsAsHeader): a fuzzer found a 580-byte
/// file whose binary data held a second header ("COLUMNS ...", "POINTS 2100000000") that made PCL allocate 67 GB.
void requireNoHeaderPclReadsAfterData(std::istream& in, const std::string& path) {
  if (const auto word = dataPclReadsAsHeader(in))
    throw std::runtime_error(path + ": the data after DATA begins like a header line ('" + *word +
                             "'), which PCL would read as one; not a PCD file");
}
}  // namespace

PcdHeader readPcdHeader(std::istream& in, const std::string& path) {
  PcdHeader header = readPcdHeaderToData(in, path);
  requireNoHeaderPclReadsAfterData(in, path);
  return header;
}

PcdHeader readPcdHeaderToData(std::istream& in, const std::string& path) {
  HeaderLines lines(in, path);
  Reading reading;
  std::string line;
  while (lines.next(line)) {
    if (line.empty()) continue;
    if (!printable(line)) lines.fail("a control character or a byte beyond ASCII in the header; not a PCD file");
    const auto words = tokens(line);
    if (words.empty()) lines.fail("a line of blanks in the header");
    if (words[0][0] == '#') continue;
    if (words[0] == "DATA") {
      reading.header.data = dataKind(words, lines);
      requireComplete(reading, lines);
      const auto position = in.tellg();
      reading.header.data_offset = position == std::streampos(-1) ? kLargest : static_cast<std::uint64_t>(position);
      return reading.header;
    }
    const auto found =
        std::find_if(kKeywords.begin(), kKeywords.end(), [&](const char* keyword) { return words[0] == keyword; });
    if (found == kKeywords.end())
      lines.fail("unknown header keyword '" + words[0].substr(0, 32) +
                 "' (expected VERSION, FIELDS, SIZE, TYPE, COUNT, WIDTH, HEIGHT, VIEWPOINT, POINTS or DATA); "
                 "not a PCD file");
    const auto keyword = static_cast<Keyword>(found - kKeywords.begin());
    if (reading.seen[keyword]) lines.fail(words[0] + " appears twice");
    readKeywordLine(keyword, words, reading, lines);
    reading.seen[keyword] = true;
  }
  lines.fail("the header ends without a DATA line; not a PCD file");
}

void requirePcdDataFitsFile(std::istream& in, const PcdHeader& header, const std::string& path) {
  std::error_code error;
  const std::uint64_t size = std::filesystem::file_size(path, error);
  const std::uint64_t available = error || size < header.data_offset ? 0 : size - header.data_offset;
  const std::uint64_t bytes = saturatingProduct(header.points, header.pointBytes());
  const auto refuse = [&](const std::string& what) {
    throw std::runtime_error(path + ": the header declares more points than the file holds (" +
                             std::to_string(header.points) + " points of " + std::to_string(header.pointBytes()) +
                             " bytes; " + what + ")");
  };
  switch (header.data) {
    case PcdHeader::Data::binary:
      if (bytes > available) refuse(std::to_string(available) + " bytes of data");
      return;
    case PcdHeader::Data::ascii:
      // Every value takes at least one character.
      if (saturatingProduct(header.points, header.pointValues()) > available)
        refuse(std::to_string(available) + " bytes of text");
      return;
    case PcdHeader::Data::binary_compressed: break;
  }
  // LZF data starts with its compressed and uncompressed sizes (little-endian 32-bit, as PCL writes them); PCL
  // allocates the uncompressed size it finds there, so both must agree with the header and the file.
  std::array<unsigned char, 8> sizes{};
  in.clear();
  in.seekg(static_cast<std::streamoff>(header.data_offset));
  if (available < sizes.size() || !in.read(reinterpret_cast<char*>(sizes.data()), sizes.size()))
    refuse("the compressed data has no sizes");
  const auto word = [&sizes](std::size_t at) {
    return std::uint64_t{sizes[at]} | std::uint64_t{sizes[at + 1]} << 8 | std::uint64_t{sizes[at + 2]} << 16 |
           std::uint64_t{sizes[at + 3]} << 24;
  };
  const std::uint64_t compressed = word(0), uncompressed = word(4);
  if (compressed > available - sizes.size())
    refuse(std::to_string(compressed) + " compressed bytes declared, " + std::to_string(available - sizes.size()) +
           " in the file");
  if (uncompressed != bytes) refuse("the compressed data says " + std::to_string(uncompressed) + " bytes uncompressed");
  if (uncompressed > saturatingProduct(compressed, kLzfMaxExpansion))
    refuse(std::to_string(compressed) + " compressed bytes cannot expand to " + std::to_string(uncompressed));
}

}  // namespace weighted_icp::io::detail
