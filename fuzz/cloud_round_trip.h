#pragma once
// The one check both cloud fuzz targets make, for PCD and for PLY: our loader refuses clearly or loads, and a
// cloud that loads saves and loads back to the same points.

#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_support.h"
#include "weighted_icp/io/cloud_io.h"

namespace weighted_icp::fuzz {

/// @brief Checks one fuzz input as a weighted landmark cloud file of the given format.
/// @param data,size the input
/// @param extension ".pcd" or ".ply": the format io::loadLandmarkCloud and io::saveLandmarkCloud pick by name
inline void checkCloudRoundTrip(const std::uint8_t* data, std::size_t size, const std::string& extension) {
  const std::string path = writeInput("cloud" + extension, {reinterpret_cast<const char*>(data), size});
  LandmarkCloud::Ptr cloud;
  if (!refusedClearlyOrParsed(path, [&] { cloud = io::loadLandmarkCloud(path); })) return;
  require(cloud != nullptr, "the loader returned no cloud");
  if (cloud->empty()) return;  // PCL writes no PLY without points; saving refuses it, as documented
  const std::string saved = (scratchFolder() / ("saved" + extension)).string();
  io::saveLandmarkCloud(*cloud, saved);
  const auto reloaded = io::loadLandmarkCloud(saved);
  require(reloaded->size() == cloud->size(), "a loaded cloud saves and loads back with another point count");
  for (std::size_t i = 0; i < cloud->size(); ++i)
    require(
        (*reloaded)[i].getVector3fMap() == (*cloud)[i].getVector3fMap() && (*reloaded)[i].weight == (*cloud)[i].weight,
        "a loaded cloud saves and loads back to other points");
}

}  // namespace weighted_icp::fuzz
