#pragma once
// Textures of the RGB-D sequence's boxes: one image per face, drawn with cv::
// shapes so that corners (rectangles, checkers, letters) and blobs (circles)
// abound at every scale a camera 1-4 m away resolves; and their sampling.
// Private to the simulation library.

#include <algorithm>
#include <array>
#include <cstdint>

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace weighted_icp::simulation {

/// @brief One texture per box face. A face is numbered 2 * axis + (1 on the
/// box's + side, 0 on its - side).
using FaceTextures = std::array<cv::Mat, 6>;

/// @brief The box axis along which a face's texture columns run. Walls and box
/// sides have their texture upright (rows run down z).
inline int faceU(int axis) { return axis == 0 ? 1 : 0; }
/// @brief The box axis along which a face's texture rows run (downwards).
inline int faceV(int axis) { return axis == 2 ? 1 : 2; }

/// @brief A random texture of `width_m` x `height_m` metres (at least 8 x 8 texels).
/// @param texels_per_metre resolution
/// @param seed everything drawn comes from it
cv::Mat makeTexture(double width_m, double height_m, double texels_per_metre, std::uint64_t seed);

/// @brief The six face textures of a box of `size` (metres along its own x, y, z),
/// face k drawn from a hash of seed + k.
FaceTextures makeBoxTextures(const Eigen::Vector3d& size, double texels_per_metre, std::uint64_t seed);

/// @brief The six face textures of a box of `size`, every one the same `tile` repeated across it from its
/// top-left corner: what perceptual aliasing looks like (one wallpaper everywhere).
/// @param tile CV_8UC3, e.g. a makeTexture of a square metre
FaceTextures makeRepeatedBoxTextures(const Eigen::Vector3d& size, double texels_per_metre, const cv::Mat& tile);

/// @brief Bilinear sample of a CV_8UC3 texture at (col, row), clamped to its
/// edges (inline: the renderer calls it for every pixel).
inline cv::Vec3d sampleBilinear(const cv::Mat& texture, double col, double row) {
  col = std::clamp(col, 0.0, texture.cols - 1.0);
  row = std::clamp(row, 0.0, texture.rows - 1.0);
  const int c0 = std::min(static_cast<int>(col), texture.cols - 2);  // textures are at least 8 x 8
  const int r0 = std::min(static_cast<int>(row), texture.rows - 2);
  const double a = col - c0, b = row - r0;
  const cv::Vec3b* top = texture.ptr<cv::Vec3b>(r0) + c0;
  const cv::Vec3b* bottom = texture.ptr<cv::Vec3b>(r0 + 1) + c0;
  cv::Vec3d value;
  for (int k = 0; k < 3; ++k)
    value[k] = (1 - b) * ((1 - a) * top[0][k] + a * top[1][k]) + b * ((1 - a) * bottom[0][k] + a * bottom[1][k]);
  return value;
}

}  // namespace weighted_icp::simulation
