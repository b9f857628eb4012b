// Fuzz target: camera files (io/camera.h), OpenCV FileStorage YAML (or XML or JSON, which FileStorage recognises by
// their first bytes). A camera that loads must save and load back to the same values.
#include <string>

#include "fuzz_support.h"
#include "weighted_icp/io/camera.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace weighted_icp;
  const std::string path = fuzz::writeInput("camera.yaml", {reinterpret_cast<const char*>(data), size});
  PinholeCamera camera;
  if (!fuzz::refusedClearlyOrParsed(path, [&] { camera = io::loadCamera(path); })) return 0;
  const std::string saved = (fuzz::scratchFolder() / "saved.yaml").string();
  io::saveCamera(camera, saved);
  const PinholeCamera reloaded = io::loadCamera(saved);
  fuzz::require(reloaded.fx == camera.fx && reloaded.fy == camera.fy && reloaded.cx == camera.cx &&
                    reloaded.cy == camera.cy && reloaded.width == camera.width && reloaded.height == camera.height &&
                    reloaded.depth_factor == camera.depth_factor && reloaded.distortion == camera.distortion,
                "a loaded camera does not save and load back to the same values");
  return 0;
}
