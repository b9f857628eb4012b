// A synthetic RGB-D sequence written in the TUM RGB-D layout (see
// tum_export.h): images and lists frame by frame into a temporary folder
// beside the target, the ground truth through io's trajectory writer, then one
// rename.

#include "weighted_icp/simulation/tum_export.h"

#include <charconv>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <system_error>

#include <unistd.h>
#include <opencv2/imgcodecs.hpp>

#include "weighted_icp/core/rgbd_frame.h"
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

/// `dir` as a folder path ("out/" names "out"), checked: absent, empty or
/// (with `overwrite`) a folder; its parent is created.
fs::path checkedTarget(const std::string& dir, bool overwrite) {
  fs::path target = fs::path(dir).lexically_normal();
  if (!target.has_filename()) target = target.parent_path();
  if (target.empty()) throw std::runtime_error("writeTumSequence: no folder given");
  std::error_code error;
  if (fs::exists(target, error)) {
    if (!fs::is_directory(target)) throw std::runtime_error(target.string() + " exists and is not a folder");
    if (!fs::is_empty(target) && !overwrite)
      throw std::runtime_error(target.string() + " exists and is not empty; not overwriting it");
  }
  const fs::path parent = target.has_parent_path() ? target.parent_path() : fs::path(".");
  fs::create_directories(parent, error);
  if (error) throw std::runtime_error("cannot create " + parent.string() + ": " + error.message());
  return target;
}

/// A new folder beside the target, so the final rename stays on one file system.
fs::path makeTemporaryFolder(const fs::path& target) {
  const fs::path parent = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::error_code error;
  for (int attempt = 0;; ++attempt) {
    const fs::path temporary =
        parent / (target.filename().string() + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(attempt));
    if (fs::create_directory(temporary, error)) return temporary;
    if (error) throw std::runtime_error("cannot write in " + parent.string() + ": " + error.message());
  }
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

/// Renames `temporary` to `target`. A non-empty target is moved aside first and
/// deleted after, or put back if the rename fails.
void moveIntoPlace(const fs::path& temporary, const fs::path& target) {
  if (!fs::exists(target) || fs::is_empty(target)) {
    fs::rename(temporary, target);  // replaces an empty folder
    return;
  }
  const fs::path old = temporary.string() + ".old";
  fs::rename(target, old);
  std::error_code error;
  fs::rename(temporary, target, error);
  if (error) {
    fs::rename(old, target);
    throw fs::filesystem_error("rename", temporary, target, error);
  }
  fs::remove_all(old, error);
}

}  // namespace

void writeTumSequence(const SyntheticRgbdSequence& sequence, const std::string& dir, bool overwrite,
                      const std::function<void(std::size_t)>& frame_written) {
  const fs::path target = checkedTarget(dir, overwrite);
  const fs::path temporary = makeTemporaryFolder(target);
  std::error_code error;
  try {
    writeFrames(sequence, temporary, frame_written);
    moveIntoPlace(temporary, target);
  } catch (const fs::filesystem_error& e) {
    fs::remove_all(temporary, error);
    throw std::runtime_error("cannot write " + target.string() + ": " + e.code().message());
  } catch (...) {
    fs::remove_all(temporary, error);
    throw;
  }
}

}  // namespace weighted_icp::simulation
