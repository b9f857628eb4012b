// Fuzz target: TUM trajectory files (io/trajectory.h). A trajectory that reads must write and read back to the
// same poses, and associate with itself one to one.
#include <string>

#include "fuzz_support.h"
#include "weighted_icp/io/trajectory.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace weighted_icp;
  const std::string path = fuzz::writeInput("trajectory.txt", {reinterpret_cast<const char*>(data), size});
  Trajectory trajectory;
  if (!fuzz::refusedClearlyOrParsed(path, [&] { trajectory = io::readTrajectory(path); })) return 0;
  const std::string saved = (fuzz::scratchFolder() / "saved.txt").string();
  io::writeTrajectory(trajectory, saved);
  const Trajectory reread = io::readTrajectory(saved);
  fuzz::require(reread.size() == trajectory.size(), "a written trajectory reads back with another pose count");
  for (std::size_t i = 0; i < reread.size(); ++i)
    fuzz::require(reread[i].timestamp == trajectory[i].timestamp && reread[i].pose.isApprox(trajectory[i].pose, 1e-9),
                  "a written trajectory reads back with other poses");
  fuzz::require(io::associate(trajectory, trajectory, 1e-9).size() == trajectory.size(),
                "a trajectory does not associate one to one with itself");
  return 0;
}
