#include "weighted_icp/io/cloud_io.h"

#include <filesystem>
#include <stdexcept>

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
}  // namespace

void saveLandmarkCloud(const LandmarkCloud& cloud, const std::string& path) {
  const std::string ext = extension(path);
  if (ext != ".pcd" && ext != ".ply")
    throw std::runtime_error("cannot save " + path + ": the extension must be .pcd or .ply");
  writeAtomically(path, [&](const std::string& temporary) {
    const int status = ext == ".pcd" ? pcl::io::savePCDFileBinary(temporary, cloud)
                                     : pcl::io::savePLYFileBinary(temporary, cloud);
    if (status != 0) throw std::runtime_error("cannot write " + path);
  });
}

LandmarkCloud::Ptr loadLandmarkCloud(const std::string& path) {
  const std::string ext = extension(path);
  if (!std::filesystem::exists(path)) throw std::runtime_error(path + ": no such file");
  auto cloud = std::make_shared<LandmarkCloud>();
  int status = -1;
  if (ext == ".pcd") status = pcl::io::loadPCDFile(path, *cloud);
  else if (ext == ".ply") status = pcl::io::loadPLYFile(path, *cloud);
  else throw std::runtime_error("cannot load " + path + ": the extension must be .pcd or .ply");
  if (status != 0) throw std::runtime_error(path + ": not a readable " + ext.substr(1) + " point cloud");
  return cloud;
}

}  // namespace weighted_icp::io
