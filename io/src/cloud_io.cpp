// Weighted landmark clouds as binary PCD/PLY through PCL, checked both ways: what is written must load back.
#include "weighted_icp/io/cloud_io.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <system_error>
#include <utility>
#include <vector>

#include <pcl/PCLPointCloud2.h>
#include <pcl/common/io.h>
#include <pcl/console/print.h>
#include <pcl/conversions.h>
#include <pcl/exceptions.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>

#include "pcd_header.h"
#include "ply_header.h"
#include "weighted_icp/io/atomic_file.h"

namespace weighted_icp::io {

namespace {
std::string extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (auto& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

/// PCL's what() starts with ": " when the exception names no source file.
std::string pclMessage(const pcl::PCLException& e) {
  const std::string message = e.what();
  return message.rfind(": ", 0) == 0 ? message.substr(2) : message;
}

/// PCL prints its own errors on stderr ("[pcl::PCDReader::read] ..."), then
/// returns a status we turn into one message of ours: while an object of this
/// class lives, PCL prints nothing. The level is global, so it is restored.
class QuietPcl {
 public:
  QuietPcl() : level_(pcl::console::getVerbosityLevel()) { pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS); }
  ~QuietPcl() { pcl::console::setVerbosityLevel(level_); }
  QuietPcl(const QuietPcl&) = delete;
  QuietPcl& operator=(const QuietPcl&) = delete;

 private:
  pcl::console::VERBOSITY_LEVEL level_;
};

std::string typeName(std::uint8_t datatype) {
  return std::string(1, pcl::getFieldType(datatype)) + std::to_string(8 * pcl::getFieldSize(datatype));
}

/// PCL fills a field it does not find with zeros and only warns, so a plain
/// x y z cloud would load with every weight 0: refuse it instead.
void requireLandmarkFields(const pcl::PCLPointCloud2& blob, const std::string& path) {
  for (const auto& expected : pcl::getFields<LandmarkPoint>()) {
    const auto found = std::find_if(blob.fields.begin(), blob.fields.end(),
                                    [&](const pcl::PCLPointField& f) { return f.name == expected.name; });
    if (found == blob.fields.end())
      throw std::runtime_error(path + ": no field '" + expected.name + "'; not a weighted landmark cloud");
    if (found->datatype != expected.datatype || found->count != expected.count)
      throw std::runtime_error(path + ": field '" + expected.name + "' is " + typeName(found->datatype) + " x" +
                               std::to_string(found->count) + ", expected " + typeName(expected.datatype) + " x" +
                               std::to_string(expected.count));
  }
}

void requireValidPoints(const LandmarkCloud& cloud, const std::string& path) {
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const LandmarkPoint& p = cloud[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      throw std::runtime_error(path + ": point " + std::to_string(i) + " has a non-finite position");
    if (!std::isfinite(p.weight) || p.weight < 0.0)
      throw std::runtime_error(path + ": point " + std::to_string(i) + " has weight " + std::to_string(p.weight) +
                               "; weights must be finite and >= 0");
  }
}

/// fromPCLPointCloud2 trusts the blob: width x height points of point_step
/// bytes, rows row_step apart, each field within a point. PCL's readers can
/// return a blob that breaks this (a PLY header with a broken line gave points
/// and no point count: fuzz/fuzz_cloud_ply), so it is checked first.
void requireConsistentBlob(const pcl::PCLPointCloud2& blob, const std::string& path) {
  const std::uint64_t points = std::uint64_t{blob.width} * blob.height;
  bool consistent = points > 0 && std::uint64_t{blob.row_step} >= std::uint64_t{blob.width} * blob.point_step &&
                    blob.data.size() >= std::uint64_t{blob.row_step} * blob.height;
  for (const auto& field : blob.fields) {
    const auto bytes = static_cast<std::uint64_t>(pcl::getFieldSize(field.datatype)) * field.count;
    consistent = consistent && std::uint64_t{field.offset} + bytes <= blob.point_step;
  }
  if (!consistent)
    throw std::runtime_error(path + ": the point data does not match the header (" + std::to_string(points) +
                             " points of " + std::to_string(blob.point_step) + " bytes, " +
                             std::to_string(blob.data.size()) + " bytes of data)");
}

/// The vertex count a PLY header declares; nullopt if the file is not PLY or declares none.
std::optional<std::uint64_t> plyVertexCount(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  if (!std::getline(in, line) || (line != "ply" && line != "ply\r")) return std::nullopt;
  while (std::getline(in, line) && line.rfind("end_header", 0) != 0) {
    std::istringstream fields(line);
    std::string keyword, element;
    std::uint64_t count = 0;
    if (fields >> keyword >> element >> count && keyword == "element" && element == "vertex") return count;
  }
  return std::nullopt;
}

/// Bytes of one value of a PLY property type, 0 for a type we do not know.
std::size_t plyTypeSize(const std::string& type) {
  static const std::pair<const char*, std::size_t> kSizes[] = {
      {"char", 1},  {"uchar", 1},   {"int8", 1},   {"uint8", 1},  {"short", 2}, {"ushort", 2},
      {"int16", 2}, {"uint16", 2},  {"int", 4},    {"uint", 4},   {"int32", 4}, {"uint32", 4},
      {"float", 4}, {"float32", 4}, {"double", 8}, {"float64", 8}};
  for (const auto& [name, size] : kSizes)
    if (type == name) return size;
  return 0;
}

/// The size a complete binary PLY file has, from its own header: the header
/// plus, for each element, its count times the bytes of its properties.
/// nullopt when the header cannot say (list properties, an unknown type).
std::optional<std::uintmax_t> plyExpectedSize(std::istream& in) {
  std::string line;
  std::uintmax_t data = 0, count = 0, element_bytes = 0;
  while (std::getline(in, line) && line.rfind("end_header", 0) != 0) {
    std::istringstream fields(line);
    std::string keyword, type;
    fields >> keyword;
    if (keyword == "element") {
      data += count * element_bytes;
      std::string name;
      if (!(fields >> name >> count)) return std::nullopt;
      element_bytes = 0;
    } else if (keyword == "property") {
      fields >> type;
      const std::size_t size = plyTypeSize(type);
      if (size == 0) return std::nullopt;  // "list" or unknown
      element_bytes += size;
    }
  }
  if (!in) return std::nullopt;
  data += count * element_bytes;
  return static_cast<std::uintmax_t>(in.tellg()) + data;
}

/// The size a complete binary PCD file has, from its own header; nullopt when
/// the header is not a well-formed one of binary data.
std::optional<std::uintmax_t> pcdExpectedSize(std::istream& in, const std::string& path) {
  try {
    const auto header = detail::readPcdHeader(in, path);
    if (header.data != detail::PcdHeader::Data::binary) return std::nullopt;
    return header.data_offset + header.points * header.pointBytes();
  } catch (const std::runtime_error&) {
    return std::nullopt;
  }
}

pcl::PCLPointCloud2 readPcd(const std::string& path) {
  pcl::PCDReader reader;
  pcl::PCLPointCloud2 blob;
  Eigen::Vector4f origin;
  Eigen::Quaternionf orientation;
  int version = 0, data_type = 0;
  unsigned int data_index = 0;
  // PCL allocates what a header declares before reading any data, and reads
  // leniently what it does not understand: only a header that passes our
  // strict reader, with data the file really holds, reaches it.
  {
    std::ifstream in(path, std::ios::binary);
    detail::requirePcdDataFitsFile(in, detail::readPcdHeader(in, path), path);
  }
  if (reader.readHeader(path, blob, origin, orientation, version, data_type, data_index) != 0 || blob.fields.empty() ||
      data_index == 0)
    throw std::runtime_error(path + ": not a PCD file (no valid header)");
  if (reader.read(path, blob) != 0) throw std::runtime_error(path + ": not a readable pcd point cloud");
  return blob;
}

/// PCL's writers do not check their streams (its PLY writer reports nothing on
/// a full disk): the written file is measured against what its header
/// promises, so a truncated file is never renamed into place.
void requireCompleteFile(const std::string& temporary, const std::string& ext, const std::string& path) {
  std::ifstream in(temporary, std::ios::binary);
  const auto expected = ext == ".ply" ? plyExpectedSize(in) : pcdExpectedSize(in, temporary);
  std::error_code error;
  const std::uintmax_t actual = std::filesystem::file_size(temporary, error);
  if (!expected || error)
    throw std::runtime_error("cannot write " + path + ": the written file has no complete header (disk full?)");
  if (actual != *expected)
    throw std::runtime_error("cannot write " + path + ": " + std::to_string(actual) + " bytes written of " +
                             std::to_string(*expected) + " (disk full?)");
}

/// True when a binary PCD we wrote has data whose first bytes PCL's header reader would take as more header (the
/// float bytes happen to spell a keyword line): PCL would misread it, and our loader refuses it.
bool pclMisreadsBinaryData(const std::string& file) {
  std::ifstream in(file, std::ios::binary);
  try {
    if (detail::readPcdHeaderToData(in, file).data != detail::PcdHeader::Data::binary) return false;
  } catch (const std::runtime_error&) {
    return false;  // an incomplete header: requireCompleteFile says so
  }
  return detail::dataPclReadsAsHeader(in).has_value();
}

/// The cloud as an ASCII PCD, every value with enough digits to read back exactly (17 significant digits: the
/// weight is a double), checked by loading it back, since PCL's writer reports no write error.
void writeAsciiPcd(const LandmarkCloud& cloud, const std::string& temporary, const std::string& path) {
  pcl::PCDWriter writer;
  if (writer.writeASCII(temporary, cloud, 17) != 0) throw std::runtime_error("cannot write " + path);
  std::error_code error;
  if (std::filesystem::file_size(temporary, error) == 0 || error)
    throw std::runtime_error("cannot write " + path + " (disk full?)");
}

/// A point that would not load back (loadLandmarkCloud refuses it) is refused
/// before writing: a position beyond float's range is stored as infinity.
void requireWritablePoints(const LandmarkCloud& cloud, const std::string& path) {
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const LandmarkPoint& p = cloud[i];
    std::ostringstream where;
    where << "cannot save " << path << ": point " << i << " (" << p.x << " " << p.y << " " << p.z << ", weight "
          << p.weight << ")";
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      throw std::runtime_error(where.str() +
                               " has a non-finite position (beyond float's range?); it would not load back");
    if (!std::isfinite(p.weight) || p.weight < 0.0)
      throw std::runtime_error(where.str() + " has a weight that is not finite and >= 0; it would not load back");
  }
}
}  // namespace

void saveLandmarkCloud(const LandmarkCloud& cloud, const std::string& path) {
  const std::string ext = extension(path);
  if (ext != ".pcd" && ext != ".ply")
    throw std::runtime_error("cannot save " + path + ": the extension must be .pcd or .ply");
  if (ext == ".ply" && cloud.empty())
    throw std::runtime_error("cannot save " + path + ": PCL cannot write a PLY file without points; use .pcd");
  requireWritablePoints(cloud, path);
  writeAtomically(path, [&](const std::string& temporary) {
    const QuietPcl quiet;
    int status = -1;
    try {
      status =
          ext == ".pcd" ? pcl::io::savePCDFileBinary(temporary, cloud) : pcl::io::savePLYFileBinary(temporary, cloud);
    } catch (const pcl::PCLException& e) {  // e.g. the folder does not exist; its message has no path
      throw std::runtime_error("cannot write " + path + " (" + pclMessage(e) + ")");
    }
    if (status != 0) throw std::runtime_error("cannot write " + path);
    if (ext == ".pcd" && pclMisreadsBinaryData(temporary)) {
      // Rare (the data's first bytes spell a header keyword), but then PCL would misread the binary file: ASCII
      // data never begins with a keyword. Verified by loading it back: PCL's ASCII writer reports no write error.
      writeAsciiPcd(cloud, temporary, path);
      const pcl::PCLPointCloud2 blob = readPcd(temporary);
      const std::size_t loaded = static_cast<std::size_t>(blob.width) * blob.height;
      if (loaded != cloud.size() || blob.data.size() != loaded * blob.point_step)
        throw std::runtime_error("cannot write " + path + ": " + std::to_string(loaded) + " of " +
                                 std::to_string(cloud.size()) + " points written (disk full?)");
      return;
    }
    requireCompleteFile(temporary, ext, path);
  });
}

LandmarkCloud::Ptr loadLandmarkCloud(const std::string& path) {
  const std::string ext = extension(path);
  if (ext != ".pcd" && ext != ".ply")
    throw std::runtime_error("cannot load " + path + ": the extension must be .pcd or .ply");
  if (!std::filesystem::exists(path)) throw std::runtime_error(path + ": no such file");
  if (!std::filesystem::is_regular_file(path)) throw std::runtime_error(path + ": not a regular file");
  auto cloud = std::make_shared<LandmarkCloud>();
  pcl::PCLPointCloud2 blob;
  const QuietPcl quiet;
  try {
    if (ext == ".pcd") {
      blob = readPcd(path);
    } else {
      {
        // PCL's PLY parser reads every element as often as its header says, before we could check anything.
        std::ifstream in(path, std::ios::binary);
        detail::requireWellFormedPlyHeader(in, path, std::filesystem::file_size(path));
      }
      const auto vertices = plyVertexCount(path);
      if (!vertices) throw std::runtime_error(path + ": not a PLY file with a vertex element");
      // PCL's PLY reader crashes on a file without vertices; it is an empty cloud.
      if (*vertices == 0) return cloud;
      // As PCD's: PCL allocates the declared vertices first; each takes at least one byte of the file.
      if (*vertices > std::filesystem::file_size(path))
        throw std::runtime_error(path + ": the header declares more points than the file holds (" +
                                 std::to_string(*vertices) + " vertices in a file of " +
                                 std::to_string(std::filesystem::file_size(path)) + " bytes)");
      if (pcl::io::loadPLYFile(path, blob) != 0) throw std::runtime_error(path + ": not a readable ply point cloud");
    }
  } catch (const std::bad_alloc&) {  // PCL allocates what the header declares
    throw std::runtime_error(path + ": the header declares more points than fit in memory");
  } catch (const std::length_error&) {  // a negative count, read as a huge unsigned one
    throw std::runtime_error(path + ": the header declares an impossible number of points (negative or too large)");
  } catch (const std::logic_error& e) {  // PCL's header parser indexes its tokens with at() (fuzz/fuzz_cloud_pcd)
    throw std::runtime_error(path + ": not a readable " + ext.substr(1) + " point cloud (malformed header line)");
  } catch (const pcl::PCLException& e) {
    throw std::runtime_error(path + ": not a readable " + ext.substr(1) + " point cloud (" + pclMessage(e) + ")");
  }
  requireLandmarkFields(blob, path);
  // fromPCLPointCloud2 takes a reference to the first byte of the data, which
  // an empty cloud does not have (undefined behaviour).
  if (blob.data.empty() && std::uint64_t{blob.width} * blob.height == 0) return cloud;
  requireConsistentBlob(blob, path);
  pcl::fromPCLPointCloud2(blob, *cloud);
  requireValidPoints(*cloud, path);
  return cloud;
}

}  // namespace weighted_icp::io
