// Fuzz target: weighted landmark clouds as PLY through our loader (io/cloud_io.h), which guards PCL's reader.
// A cloud that loads must save and load back to the same points (cloud_round_trip.h).
#include "cloud_round_trip.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  weighted_icp::fuzz::checkCloudRoundTrip(data, size, ".ply");
  return 0;
}
