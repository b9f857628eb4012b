// The camera of a TUM folder: --camera, the folder's camera.yaml or its name (see dataset_camera.h).

#include "dataset_camera.h"

#include <filesystem>
#include <stdexcept>

#include "weighted_icp/io/camera.h"

namespace weighted_icp::tools {

namespace fs = std::filesystem;

namespace {

/// TUM folders are named after their sensor (rgbd_dataset_freiburg3_teddy, tum_fr1_xyz_head).
std::string cameraFromFolderName(const std::string& dir) {
  // The folder's own name only ("data/", "data/." and "data" alike), not its parents'.
  const std::string name = fs::weakly_canonical(fs::absolute(dir)).filename().string();
  for (const char* sensor : {"1", "2", "3"})
    if (name.find(std::string("freiburg") + sensor) != std::string::npos ||
        name.find(std::string("fr") + sensor) != std::string::npos)
      return std::string("fr") + sensor;
  throw std::runtime_error("cannot tell the camera of " + dir +
                           " from its name and it has no camera.yaml; pass --camera fr1|fr2|fr3|FILE.yaml");
}

}  // namespace

PinholeCamera datasetCamera(const std::string& dataset, const std::string& spec) {
  if (!spec.empty()) return io::loadCamera(spec);
  const fs::path own = fs::path(dataset) / "camera.yaml";
  if (fs::is_regular_file(own)) return io::loadCamera(own.string());
  return io::loadCamera(cameraFromFolderName(dataset));
}

}  // namespace weighted_icp::tools
