// Fuzz target: the session folder wicp_rgbd_slam writes and wicp_merge reads (mapping/session.h): one input is
// session.txt, camera.yaml, keyframes.txt, landmarks.txt and frames.txt, split at "\n@@\n" lines (a missing part
// is an empty file). A session that loads must be consistent, save and load back to the same records, and turn
// into a front-end map (or refuse to, for keyframe ids with gaps, as documented).
#include <stdexcept>
#include <string>

#include "fuzz_support.h"
#include "weighted_icp/mapping/session.h"

namespace {
const char* const kFiles[] = {"session.txt", "camera.yaml", "keyframes.txt", "landmarks.txt", "frames.txt"};

bool sameShape(const weighted_icp::mapping::Session& a, const weighted_icp::mapping::Session& b) {
  if (a.keyframes.size() != b.keyframes.size() || a.points.size() != b.points.size() ||
      a.frames.size() != b.frames.size())
    return false;
  for (std::size_t i = 0; i < a.keyframes.size(); ++i)
    if (a.keyframes[i].id != b.keyframes[i].id || a.keyframes[i].keypoints.size() != b.keyframes[i].keypoints.size() ||
        a.keyframes[i].observed_points != b.keyframes[i].observed_points ||
        !a.keyframes[i].pose_wc.isApprox(b.keyframes[i].pose_wc, 1e-9))
      return false;
  for (std::size_t i = 0; i < a.points.size(); ++i)
    if (a.points[i].id != b.points[i].id || a.points[i].position != b.points[i].position ||
        a.points[i].observations.size() != b.points[i].observations.size())
      return false;
  return true;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace weighted_icp;
  const auto parts = fuzz::splitParts({reinterpret_cast<const char*>(data), size}, 5);
  for (std::size_t i = 0; i < 5; ++i)
    fuzz::writeInput(std::string("session/") + kFiles[i], i < parts.size() ? parts[i] : std::string_view());
  const std::string folder = (fuzz::scratchFolder() / "session").string();
  mapping::Session session;
  // Errors name the folder or a file in it: the folder is the common part.
  if (!fuzz::refusedClearlyOrParsed(folder, [&] { session = mapping::loadSession(folder); })) return 0;
  try {
    session.validate();
  } catch (const std::invalid_argument& error) {
    fuzz::require(false, std::string("a loaded session is inconsistent: ") + error.what());
  }
  const std::string saved = (fuzz::scratchFolder() / "saved").string();
  mapping::saveSession(session, saved, true);
  const mapping::Session reread = mapping::loadSession(saved);
  fuzz::require(sameShape(session, reread), "a session does not save and load back to the same records");
  session.trajectory();
  try {
    session.toMap();
  } catch (const std::invalid_argument&) {
    // Keyframe ids other than 0, 1, 2, ...: documented, and not a map wicp_merge can use.
  }
  return 0;
}
