// Fuzz target: weighted landmark clouds as PLY through our loader (io/cloud_io.h), which guards PCL's reader.
// A cloud that loads must save and load back to the same points.
#include <string>

#include "fuzz_support.h"
#include "weighted_icp/io/cloud_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace weighted_icp;
  const std::string path = fuzz::writeInput("cloud.ply", {reinterpret_cast<const char*>(data), size});
  LandmarkCloud::Ptr cloud;
  if (!fuzz::refusedClearlyOrParsed(path, [&] { cloud = io::loadLandmarkCloud(path); })) return 0;
  fuzz::require(cloud != nullptr, "the loader returned no cloud");
  if (cloud->empty()) return 0;  // PCL writes no PLY without points; saving refuses it, as documented
  const std::string saved = (fuzz::scratchFolder() / "saved.ply").string();
  io::saveLandmarkCloud(*cloud, saved);
  const auto reloaded = io::loadLandmarkCloud(saved);
  fuzz::require(reloaded->size() == cloud->size(), "a loaded cloud saves and loads back with another point count");
  for (std::size_t i = 0; i < cloud->size(); ++i)
    fuzz::require(
        (*reloaded)[i].getVector3fMap() == (*cloud)[i].getVector3fMap() && (*reloaded)[i].weight == (*cloud)[i].weight,
        "a loaded cloud saves and loads back to other points");
  return 0;
}
