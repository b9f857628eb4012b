// Fuzz target: the paper's landmark map format (io/map_format.h). A map that parses must also write, read back
// to the same text, and give every landmark its metrics and mini-maps without throwing.
#include <sstream>
#include <string>

#include "fuzz_support.h"
#include "weighted_icp/io/map_format.h"

namespace {
std::string written(const weighted_icp::LandmarkMap& map) {
  std::ostringstream out;
  weighted_icp::io::writeLandmarkMap(map, out);
  return out.str();
}

/// The same map up to rounding of the frames' rotations (a quaternion read, normalised, turned into a matrix and
/// back need not give the same last bits); landmarks are written exactly.
bool sameMap(const weighted_icp::LandmarkMap& a, const weighted_icp::LandmarkMap& b) {
  if (a.frames.size() != b.frames.size() || a.landmarks.size() != b.landmarks.size()) return false;
  for (auto i = a.frames.begin(), j = b.frames.begin(); i != a.frames.end(); ++i, ++j)
    if (i->first != j->first || i->second.translation() != j->second.translation() ||
        !i->second.linear().isApprox(j->second.linear(), 1e-12))
      return false;
  for (std::size_t i = 0; i < a.landmarks.size(); ++i) {
    const auto &p = a.landmarks[i], &q = b.landmarks[i];
    if (p.id != q.id || p.position != q.position || p.covariance != q.covariance ||
        p.observations.size() != q.observations.size())
      return false;
    for (std::size_t k = 0; k < p.observations.size(); ++k)
      if (p.observations[k].frame_id != q.observations[k].frame_id || p.observations[k].u != q.observations[k].u ||
          p.observations[k].v != q.observations[k].v)
        return false;
  }
  return true;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace weighted_icp;
  const std::string source = "fuzz_map.txt";
  LandmarkMap map;
  const bool parsed = fuzz::refusedClearlyOrParsed(source, [&] {
    std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
    map = io::parseLandmarkMap(in, source);
  });
  if (!parsed) return 0;
  // Everything the tools do with a map they have read: a parsed map is a valid one.
  std::istringstream again(written(map));
  const LandmarkMap reread = io::parseLandmarkMap(again, "written map");
  fuzz::require(sameMap(map, reread), "a parsed map does not write and read back to the same map");
  for (const auto& landmark : map.landmarks) map.metrics(landmark);
  map.withMinObservations(2);
  if (!map.frames.empty()) map.splitIntoMiniMaps(40);
  return 0;
}
