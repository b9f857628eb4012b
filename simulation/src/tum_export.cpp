// A synthetic RGB-D sequence written in the TUM RGB-D layout (see
// tum_export.h): images and lists frame by frame into io::AtomicFolder's
// temporary folder beside the target, the ground truth through io's trajectory
// writer, the camera through io's camera writer, then one rename.

#include "weighted_icp/simulation/tum_export.h"

#include <charconv>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>

#include "weighted_icp/core/rgbd_frame.h"
#include "weighted_icp/io/atomic_folder.h"
#include "weighted_icp/io/camera.h"
#include "weighted_icp/io/trajectory.h"

namespace weighted_icp::simulation {

namespace {

namespace fs = std::filesystem;

std::string timestampText(double timestamp) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.6f", timestamp);
  return text;
}

/// The value a reader gets from the listed text, so that groundtruth.txt's
/// timestamps equal rgb.txt's, as they did when they were the same text.
double listedTimestamp(const std::string& text) {
  double value = 0.0;
  std::from_chars(text.data(), text.data() + text.size(), value);
  return value;
}

void writeImage(const fs::path& path, const cv::Mat& image) {
  if (!cv::imwrite(path.string(), image)) throw std::runtime_error("cannot write " + path.string());
}

/// Renders every frame into `folder`: images, rgb.txt, depth.txt, groundtruth.txt.
void writeFrames(const SyntheticRgbdSequence& sequence, const fs::path& folder,
                 const std::function<void(std::size_t)>& frame_written) {
  fs::create_directory(folder / "rgb");
  fs::create_directory(folder / "depth");
  std::ofstream rgb_list(folder / "rgb.txt"), depth_list(folder / "depth.txt");
  rgb_list << "# color images\n# synthetic RGB-D sequence, seed " << sequence.options().seed
           << "\n# timestamp filename\n";
  depth_list << "# depth maps\n# synthetic RGB-D sequence, seed " << sequence.options().seed
             << "\n# timestamp filename\n";
  Trajectory groundtruth;
  for (std::size_t i = 0; i < sequence.size(); ++i) {
    const SyntheticRgbdFrame frame = sequence.frame(i);
    const std::string stamp = timestampText(frame.rgbd.timestamp);
    writeImage(folder / "rgb" / (stamp + ".png"), frame.rgbd.color);
    writeImage(folder / "depth" / (stamp + ".png"),
               depthToRaw(frame.rgbd.depth, sequence.options().camera.depth_factor));
    rgb_list << stamp << " rgb/" << stamp << ".png\n";
    depth_list << stamp << " depth/" << stamp << ".png\n";
    groundtruth.push_back({listedTimestamp(stamp), frame.camera_to_world});
    if (frame_written) frame_written(i);
  }
  for (std::ofstream* list : {&rgb_list, &depth_list}) {
    list->close();
    if (!*list) throw std::runtime_error("cannot write the lists in " + folder.string());
  }
  io::writeTrajectory(groundtruth, (folder / "groundtruth.txt").string());
}

}  // namespace

void writeTumSequence(const SyntheticRgbdSequence& sequence, const std::string& dir, bool overwrite,
                      const std::function<void(std::size_t)>& frame_written) {
  io::AtomicFolder folder(dir, overwrite);  // refuses a non-empty dir before rendering anything
  writeFrames(sequence, folder.path(), frame_written);
  // The camera the images were rendered with: the synthetic camera has fr1's intrinsics but no lens distortion,
  // so the folder must not be read as fr1 (whose distortion the tracker would then remove from exact images).
  io::saveCamera(sequence.options().camera, (folder.path() / "camera.yaml").string());
  folder.publish();
}

}  // namespace weighted_icp::simulation
