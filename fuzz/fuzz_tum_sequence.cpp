// Fuzz target: a TUM RGB-D sequence folder's lists (io/tum_sequence.h): one input is rgb.txt, depth.txt and
// optionally groundtruth.txt, split at "\n@@\n" lines. The folder holds two empty images, rgb/1.png and
// depth/1.png, so lists naming them get past the existence check; loading a frame must then refuse them clearly.
#include <filesystem>
#include <string>

#include "fuzz_support.h"
#include "weighted_icp/io/tum_sequence.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace weighted_icp;
  const auto parts = fuzz::splitParts({reinterpret_cast<const char*>(data), size}, 3);
  const std::string folder = (fuzz::scratchFolder() / "sequence").string();
  fuzz::writeInput("sequence/rgb/1.png", "");
  fuzz::writeInput("sequence/depth/1.png", "");
  fuzz::writeInput("sequence/rgb.txt", parts[0]);
  fuzz::writeInput("sequence/depth.txt", parts.size() > 1 ? parts[1] : std::string_view());
  const auto groundtruth = std::filesystem::path(folder) / "groundtruth.txt";
  if (parts.size() > 2)
    fuzz::writeInput("sequence/groundtruth.txt", parts[2]);
  else
    std::filesystem::remove(groundtruth);
  io::TumSequence sequence;
  // Errors name the folder or the list file in it: the folder is the common part.
  if (!fuzz::refusedClearlyOrParsed(folder, [&] { sequence = io::TumSequence::open(folder); })) return 0;
  fuzz::require(sequence.size() > 0, "a sequence opened without frames");
  for (std::size_t i = 0; i < sequence.size(); ++i) {
    const auto& frame = sequence.frame(i);
    fuzz::require(
        std::filesystem::is_regular_file(frame.rgb_path) && std::filesystem::is_regular_file(frame.depth_path),
        "a sequence opened with a frame whose image does not exist");
    if (sequence.hasGroundTruth()) sequence.groundTruthAt(frame.rgb_timestamp);
  }
  fuzz::refusedClearlyOrParsed(folder, [&] { sequence.loadFrame(0, tumCamera(1)); });
  return 0;
}
