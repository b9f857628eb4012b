#include "weighted_icp/io/cloud_io.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>

#include <pcl/PCLPointCloud2.h>
#include <pcl/common/io.h>
#include <pcl/conversions.h>
#include <pcl/exceptions.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>

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

pcl::PCLPointCloud2 readPcd(const std::string& path) {
  pcl::PCDReader reader;
  pcl::PCLPointCloud2 blob;
  Eigen::Vector4f origin;
  Eigen::Quaternionf orientation;
  int version = 0, data_type = 0;
  unsigned int data_index = 0;
  // PCL's reader crashes on a file whose header has no FIELDS (any non-PCD
  // file), so the header is checked before the data is read.
  if (reader.readHeader(path, blob, origin, orientation, version, data_type, data_index) != 0 || blob.fields.empty() ||
      data_index == 0)
    throw std::runtime_error(path + ": not a PCD file (no valid header)");
  if (reader.read(path, blob) != 0) throw std::runtime_error(path + ": not a readable pcd point cloud");
  return blob;
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
}  // namespace

void saveLandmarkCloud(const LandmarkCloud& cloud, const std::string& path) {
  const std::string ext = extension(path);
  if (ext != ".pcd" && ext != ".ply")
    throw std::runtime_error("cannot save " + path + ": the extension must be .pcd or .ply");
  if (ext == ".ply" && cloud.empty())
    throw std::runtime_error("cannot save " + path + ": PCL cannot write a PLY file without points; use .pcd");
  writeAtomically(path, [&](const std::string& temporary) {
    int status = -1;
    try {
      status =
          ext == ".pcd" ? pcl::io::savePCDFileBinary(temporary, cloud) : pcl::io::savePLYFileBinary(temporary, cloud);
    } catch (const pcl::PCLException& e) {  // e.g. the folder does not exist; its message has no path
      throw std::runtime_error("cannot write " + path + " (" + pclMessage(e) + ")");
    }
    if (status != 0) throw std::runtime_error("cannot write " + path);
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
  try {
    if (ext == ".pcd") {
      blob = readPcd(path);
    } else {
      const auto vertices = plyVertexCount(path);
      if (!vertices) throw std::runtime_error(path + ": not a PLY file with a vertex element");
      // PCL's PLY reader crashes on a file without vertices; it is an empty cloud.
      if (*vertices == 0) return cloud;
      if (pcl::io::loadPLYFile(path, blob) != 0) throw std::runtime_error(path + ": not a readable ply point cloud");
    }
  } catch (const std::bad_alloc&) {  // PCL allocates what the header declares
    throw std::runtime_error(path + ": the header declares more points than fit in memory");
  } catch (const pcl::PCLException& e) {
    throw std::runtime_error(path + ": not a readable " + ext.substr(1) + " point cloud (" + pclMessage(e) + ")");
  }
  requireLandmarkFields(blob, path);
  pcl::fromPCLPointCloud2(blob, *cloud);
  requireValidPoints(*cloud, path);
  return cloud;
}

}  // namespace weighted_icp::io
