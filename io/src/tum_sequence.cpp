#include "weighted_icp/io/tum_sequence.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <system_error>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "text_fields.h"

namespace weighted_icp::io {

namespace fs = std::filesystem;

namespace {

/// The benchmark's association limit between colour and depth images.
constexpr double kMaxRgbDepthDifference = 0.02;

/// An image path as a list names it, for a message: the list's entry is
/// clipped and escaped (it may be binary garbage), the folder is ours.
std::string shownImagePath(const fs::path& folder, const std::string& entry) {
  const std::string shown = detail::clipToken(entry);
  return fs::path(entry).is_absolute() ? shown : (folder / shown).string();
}

std::string sizeText(const cv::Mat& image) { return std::to_string(image.cols) + "x" + std::to_string(image.rows); }

/// Empty when `path` is a regular file, else why not in words. Asked without exceptions: std::filesystem's (a name
/// too long for the file system, a permission) would not name the list that gave the path.
std::string whyNotAnImageFile(const std::string& path) {
  std::error_code error;
  const fs::file_status status = fs::status(path, error);
  if (status.type() == fs::file_type::not_found) return "no such image file";
  if (error) return "cannot use the image file name (" + error.message() + ")";
  return fs::is_regular_file(status) ? std::string() : "no such image file";
}

cv::Mat readImage(const std::string& path, int flags) {
  if (const std::string why = whyNotAnImageFile(path); !why.empty()) throw std::runtime_error(path + ": " + why);
  cv::Mat image = cv::imread(path, flags);
  if (image.empty()) throw std::runtime_error(path + ": cannot read the image (unreadable or not an image format)");
  return image;
}

}  // namespace

TumSequence TumSequence::open(const std::string& directory) {
  if (!fs::is_directory(directory)) throw std::runtime_error(directory + ": no such folder");
  const fs::path folder(directory);
  const std::string rgb_list = (folder / "rgb.txt").string();
  const std::string depth_list = (folder / "depth.txt").string();
  const auto rgb = readTimestampedLines(rgb_list, 1);
  const auto depth = readTimestampedLines(depth_list, 1);

  const auto stamps = [](const std::vector<TimestampedLine>& lines) {
    std::vector<double> values;
    for (const auto& line : lines) values.push_back(line.timestamp);
    return values;
  };
  TumSequence sequence;
  sequence.directory_ = directory;
  for (const auto& [r, d] : associate(stamps(rgb), stamps(depth), kMaxRgbDepthDifference)) {
    TumFrame frame;
    frame.rgb_timestamp = rgb[r].timestamp;
    frame.depth_timestamp = depth[d].timestamp;
    frame.rgb_path = (folder / rgb[r].fields[0]).string();
    frame.depth_path = (folder / depth[d].fields[0]).string();
    // Checked now, so a long run does not stop at its 500th frame.
    if (const std::string why = whyNotAnImageFile(frame.rgb_path); !why.empty())
      throw std::runtime_error(rgb_list + ":" + std::to_string(rgb[r].line) + ": " + why + " " +
                               shownImagePath(folder, rgb[r].fields[0]));
    if (const std::string why = whyNotAnImageFile(frame.depth_path); !why.empty())
      throw std::runtime_error(depth_list + ":" + std::to_string(depth[d].line) + ": " + why + " " +
                               shownImagePath(folder, depth[d].fields[0]));
    sequence.frames_.push_back(std::move(frame));
  }
  if (sequence.frames_.empty())
    throw std::runtime_error(directory + ": no colour and depth images less than " +
                             std::to_string(kMaxRgbDepthDifference) + " s apart (" + std::to_string(rgb.size()) +
                             " in rgb.txt, " + std::to_string(depth.size()) + " in depth.txt)");

  const fs::path groundtruth_path = folder / "groundtruth.txt";
  if (fs::exists(groundtruth_path)) {
    Trajectory groundtruth = readTrajectory(groundtruth_path.string());
    if (groundtruth.empty()) throw std::runtime_error(groundtruth_path.string() + ": no poses");
    std::sort(groundtruth.begin(), groundtruth.end(),
              [](const StampedPose& a, const StampedPose& b) { return a.timestamp < b.timestamp; });
    sequence.groundtruth_ = std::move(groundtruth);
  }
  return sequence;
}

const TumFrame& TumSequence::frame(std::size_t index) const {
  if (index >= frames_.size())
    throw std::out_of_range(directory_ + ": frame " + std::to_string(index) + " of " + std::to_string(frames_.size()));
  return frames_[index];
}

RgbdFrame TumSequence::loadFrame(std::size_t index, const PinholeCamera& camera) const {
  if (!(std::isfinite(camera.depth_factor) && camera.depth_factor > 0.0))
    throw std::invalid_argument("the camera's depth_factor must be a finite number > 0");
  const TumFrame& paths = frame(index);
  RgbdFrame images;
  images.timestamp = paths.rgb_timestamp;
  images.color = readImage(paths.rgb_path, cv::IMREAD_COLOR);
  const cv::Mat raw_depth = readImage(paths.depth_path, cv::IMREAD_UNCHANGED);
  if (raw_depth.type() != CV_16UC1)
    throw std::runtime_error(paths.depth_path + ": a depth image must be 16-bit single-channel, found " +
                             std::to_string(raw_depth.channels()) + " channel(s) of " +
                             std::to_string(8 * raw_depth.elemSize1()) + " bits");
  const cv::Size depth_size = camera.depthImageSize();
  if (depth_size == cv::Size(camera.width, camera.height) && raw_depth.size() != images.color.size())
    throw std::runtime_error(paths.depth_path + ": depth image is " + sizeText(raw_depth) + " but the colour image " +
                             paths.rgb_path + " is " + sizeText(images.color));
  if (images.color.cols != camera.width || images.color.rows != camera.height)
    throw std::runtime_error(paths.rgb_path + ": image is " + sizeText(images.color) + " but the camera's is " +
                             std::to_string(camera.width) + "x" + std::to_string(camera.height));
  // A depth camera of its own resolution (depth_width, depth_height in the camera file).
  if (raw_depth.size() != depth_size)
    throw std::runtime_error(paths.depth_path + ": depth image is " + sizeText(raw_depth) +
                             " but the depth camera's images are " + std::to_string(depth_size.width) + "x" +
                             std::to_string(depth_size.height));
  images.depth = depthFromRaw(raw_depth, camera.depth_factor);
  return images;
}

std::optional<Eigen::Isometry3d> TumSequence::groundTruthAt(double timestamp, double max_difference) const {
  if (groundtruth_.empty()) throw std::runtime_error(directory_ + ": the sequence has no groundtruth.txt");
  const StampedPose& nearest = groundtruth_[nearestInTime(groundtruth_, timestamp)];
  if (!(std::abs(nearest.timestamp - timestamp) < max_difference)) return std::nullopt;
  return nearest.pose;
}

}  // namespace weighted_icp::io
