#pragma once
// A TUM RGB-D benchmark sequence folder: rgb.txt and depth.txt ("timestamp
// filename", paths relative to the folder), the images they name, and
// groundtruth.txt (optional; see trajectory.h). Colour and depth images are
// paired by timestamp as the benchmark's associate.py does.

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "weighted_icp/core/rgbd_frame.h"
#include "weighted_icp/io/camera.h"
#include "weighted_icp/io/trajectory.h"

namespace weighted_icp::io {

/// One associated colour/depth pair. The colour timestamp is the frame's
/// timestamp (the one estimated trajectories use).
struct TumFrame {
  double rgb_timestamp = 0.0;
  double depth_timestamp = 0.0;
  std::string rgb_path;  // folder / file name from rgb.txt
  std::string depth_path;
};

class TumSequence {
 public:
  /// Associates rgb.txt with depth.txt (differences below 0.02 s) and reads
  /// groundtruth.txt if the folder has one. Throws std::runtime_error naming
  /// the folder, or the list file and line: missing folder or list, a
  /// malformed line, an associated image file that does not exist, no pair.
  static TumSequence open(const std::string& directory);

  const std::string& directory() const { return directory_; }
  std::size_t size() const { return frames_.size(); }
  /// Frames in colour-timestamp order; throws std::out_of_range.
  const TumFrame& frame(std::size_t index) const;

  /// Reads frame `index`'s images (not undistorted), depth scaled by
  /// camera.depth_factor; the timestamp is the colour image's.
  /// Throws std::runtime_error naming the file: unreadable image, depth not
  /// 16-bit single-channel, colour and depth of different sizes, or a size
  /// other than the camera's (the depth image: the size of the camera's depth
  /// camera, PinholeCamera::depthImageSize, which may differ from the colour
  /// image's); std::invalid_argument for a camera whose depth_factor is not > 0.
  RgbdFrame loadFrame(std::size_t index, const PinholeCamera& camera) const;

  bool hasGroundTruth() const { return !groundtruth_.empty(); }
  /// Ground truth sorted by time; empty without groundtruth.txt.
  const Trajectory& groundTruth() const { return groundtruth_; }
  /// The ground-truth pose nearest in time, if it is less than max_difference
  /// away (the association rule). Throws std::runtime_error if the sequence
  /// has no ground truth.
  std::optional<Eigen::Isometry3d> groundTruthAt(double timestamp, double max_difference = 0.02) const;

 private:
  std::string directory_;
  std::vector<TumFrame> frames_;
  Trajectory groundtruth_;
};

}  // namespace weighted_icp::io
