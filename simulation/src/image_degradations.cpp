// Motion blur, noise, low light, zoom and unregistered depth (see image_degradations.h).

#include "weighted_icp/simulation/image_degradations.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace weighted_icp::simulation {

namespace {

void requireEightBit(const cv::Mat& image, const char* function) {
  if (image.empty()) throw std::invalid_argument(std::string(function) + ": empty image");
  if (image.depth() != CV_8U)
    throw std::invalid_argument(std::string(function) + ": needs an 8-bit image, got " +
                                cv::typeToString(image.type()));
}

}  // namespace

cv::Mat motionBlur(const cv::Mat& image, double length_px, double angle_deg) {
  requireEightBit(image, "motionBlur");
  if (!(length_px >= 1.0) || length_px > 200.0)
    throw std::invalid_argument("motionBlur: length must be in [1, 200] px, got " + std::to_string(length_px));
  const int size = 2 * static_cast<int>(std::ceil(length_px / 2.0)) + 1;
  cv::Mat kernel = cv::Mat::zeros(size, size, CV_32F);
  const double c = (size - 1) / 2.0, angle = angle_deg * M_PI / 180.0;
  // A segment of the given length through the centre, drawn with sub-pixel steps.
  const int steps = 4 * size;
  for (int s = 0; s <= steps; ++s) {
    const double t = (static_cast<double>(s) / steps - 0.5) * (length_px - 1.0);
    const int x = static_cast<int>(std::lround(c + t * std::cos(angle)));
    const int y = static_cast<int>(std::lround(c + t * std::sin(angle)));
    kernel.at<float>(y, x) += 1.0f;
  }
  kernel /= cv::sum(kernel)[0];
  cv::Mat blurred;
  cv::filter2D(image, blurred, -1, kernel, cv::Point(-1, -1), 0.0, cv::BORDER_REFLECT);
  return blurred;
}

cv::Mat addGaussianNoise(const cv::Mat& image, double sigma, cv::RNG& rng) {
  requireEightBit(image, "addGaussianNoise");
  if (!(sigma >= 0.0)) throw std::invalid_argument("addGaussianNoise: sigma must be >= 0");
  cv::Mat noise(image.size(), CV_MAKETYPE(CV_32F, image.channels())), noisy;
  rng.fill(noise, cv::RNG::NORMAL, 0.0, sigma);
  image.convertTo(noisy, noise.type());
  noisy += noise;
  noisy.convertTo(noisy, image.type());  // saturates
  return noisy;
}

cv::Mat noisyDepth(const cv::Mat& depth, double coefficient, double correlation_px, cv::RNG& rng) {
  if (depth.empty() || depth.type() != CV_32F) throw std::invalid_argument("noisyDepth: depth must be CV_32F metres");
  if (!(coefficient >= 0.0) || !std::isfinite(coefficient))
    throw std::invalid_argument("noisyDepth: coefficient must be >= 0");
  if (!(correlation_px >= 0.0) || !std::isfinite(correlation_px))
    throw std::invalid_argument("noisyDepth: correlation must be >= 0 px");
  cv::Mat field(depth.size(), CV_32F);
  rng.fill(field, cv::RNG::NORMAL, 0.0, 1.0);
  if (correlation_px > 0.0) {
    cv::GaussianBlur(field, field, cv::Size(), correlation_px, correlation_px, cv::BORDER_REFLECT);
    cv::Scalar mean, stddev;
    cv::meanStdDev(field, mean, stddev);
    if (stddev[0] > 0.0) field = (field - mean[0]) / stddev[0];  // unit variance again
  }
  cv::Mat noisy = depth.clone();
  for (int v = 0; v < noisy.rows; ++v) {
    float* row = noisy.ptr<float>(v);
    const float* n = field.ptr<float>(v);
    for (int u = 0; u < noisy.cols; ++u) {
      const float z = row[u];
      if (!(z > 0.0f) || !std::isfinite(z)) {
        row[u] = 0.0f;
        continue;
      }
      const float measured = z + static_cast<float>(coefficient) * z * z * n[u];
      row[u] = measured > 0.0f ? measured : 0.0f;
    }
  }
  return noisy;
}

cv::Mat lowLight(const cv::Mat& image, double gain, double gamma, double noise_sigma, cv::RNG& rng) {
  requireEightBit(image, "lowLight");
  if (!(gain > 0.0 && gain <= 1.0)) throw std::invalid_argument("lowLight: gain must be in (0, 1]");
  if (!(gamma > 0.0)) throw std::invalid_argument("lowLight: gamma must be > 0");
  cv::Mat table(1, 256, CV_8U);
  for (int v = 0; v < 256; ++v)
    table.at<unsigned char>(v) = cv::saturate_cast<unsigned char>(255.0 * gain * std::pow(v / 255.0, gamma));
  cv::Mat dark;
  cv::LUT(image, table, dark);
  return addGaussianNoise(dark, noise_sigma, rng);
}

cv::Mat changeExposure(const cv::Mat& image, double stops) {
  requireEightBit(image, "changeExposure");
  if (!(std::abs(stops) <= 8.0)) throw std::invalid_argument("changeExposure: stops must be in [-8, 8]");
  constexpr double kGamma = 2.2;  // 8-bit values are gamma-encoded; the light adds up in linear units
  const double gain = std::pow(2.0, stops);
  cv::Mat table(1, 256, CV_8U);
  for (int v = 0; v < 256; ++v)
    table.at<unsigned char>(v) = cv::saturate_cast<unsigned char>(
        255.0 * std::pow(std::min(1.0, gain * std::pow(v / 255.0, kGamma)), 1.0 / kGamma));
  cv::Mat exposed;
  cv::LUT(image, table, exposed);
  return exposed;
}

PinholeCamera zoomedCamera(const PinholeCamera& camera, double scale) {
  if (!(scale > 0.0) || !std::isfinite(scale))
    throw std::invalid_argument("zoomedCamera: scale must be > 0, got " + std::to_string(scale));
  PinholeCamera zoomed = camera;
  zoomed.fx *= scale;
  zoomed.fy *= scale;
  if (camera.depthImageSize() != cv::Size(camera.width, camera.height))
    throw std::invalid_argument("zoomedCamera: the depth camera's images are not the colour images' size");
  if (zoomed.unregistered_depth) {  // its image is zoomed about the colour camera's principal point too
    DepthCamera& depth = *zoomed.unregistered_depth;
    depth.fx *= scale;
    depth.fy *= scale;
    depth.cx = camera.cx + scale * (depth.cx - camera.cx);
    depth.cy = camera.cy + scale * (depth.cy - camera.cy);
  }
  return zoomed;
}

cv::Mat zoomImage(const cv::Mat& image, const PinholeCamera& camera, double scale, int interpolation) {
  if (image.empty()) throw std::invalid_argument("zoomImage: empty image");
  if (image.cols != camera.width || image.rows != camera.height)
    throw std::invalid_argument("zoomImage: image is " + std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                                ", the camera " + std::to_string(camera.width) + "x" + std::to_string(camera.height));
  if (!(scale > 0.0) || !std::isfinite(scale)) throw std::invalid_argument("zoomImage: scale must be > 0");
  // u' = cx + scale (u - cx): the normalised coordinates (u - cx) / fx are kept.
  const cv::Matx23d to_zoomed(scale, 0.0, (1.0 - scale) * camera.cx, 0.0, scale, (1.0 - scale) * camera.cy);
  cv::Mat zoomed;
  cv::warpAffine(image, zoomed, to_zoomed, image.size(), interpolation, cv::BORDER_CONSTANT, cv::Scalar::all(0));
  return zoomed;
}

PinholeCamera resizedCamera(const PinholeCamera& camera, double scale) {
  if (!(scale > 0.0) || !std::isfinite(scale))
    throw std::invalid_argument("resizedCamera: scale must be > 0, got " + std::to_string(scale));
  PinholeCamera resized = camera;
  resized.width = static_cast<int>(std::lround(camera.width * scale));
  resized.height = static_cast<int>(std::lround(camera.height * scale));
  if (resized.width < 16 || resized.height < 16)
    throw std::invalid_argument("resizedCamera: " + std::to_string(camera.width) + "x" + std::to_string(camera.height) +
                                " times " + std::to_string(scale) + " is smaller than 16x16 pixels");
  // The sizes are rounded: each axis scales by its own exact ratio, as cv::resize maps it. Pixel centres: old pixel
  // u spans [u - 0.5, u + 0.5], which the new grid covers as [(u - 0.5) s, (u + 0.5) s].
  const double sx = static_cast<double>(resized.width) / camera.width;
  const double sy = static_cast<double>(resized.height) / camera.height;
  const auto centre = [](double c, double s) { return (c + 0.5) * s - 0.5; };
  resized.fx *= sx;
  resized.fy *= sy;
  resized.cx = centre(camera.cx, sx);
  resized.cy = centre(camera.cy, sy);
  if (resized.unregistered_depth) {
    DepthCamera& depth = *resized.unregistered_depth;
    if (depth.width > 0 && depth.height > 0) {  // a depth camera of its own size: resized by its own ratios
      const cv::Size old_size = camera.depthImageSize();
      depth.width = std::max(1, static_cast<int>(std::lround(old_size.width * scale)));
      depth.height = std::max(1, static_cast<int>(std::lround(old_size.height * scale)));
      depth = depth.resampled(static_cast<double>(depth.width) / old_size.width,
                              static_cast<double>(depth.height) / old_size.height);
    } else {
      depth = depth.resampled(sx, sy);
    }
  }
  return resized;
}

namespace {

/// The rows croppedCamera keeps: the first one and how many.
std::pair<int, int> croppedRows(const PinholeCamera& camera, double aspect) {
  const double widest = static_cast<double>(camera.width) / camera.height;
  if (!std::isfinite(aspect) || aspect < widest - 1e-9 || aspect > 4.0)
    throw std::invalid_argument("croppedCamera: aspect must be in [" + std::to_string(widest) + ", 4] (width / " +
                                "height, at least the camera's own), got " + std::to_string(aspect));
  const int rows = std::min(camera.height, static_cast<int>(std::lround(camera.width / aspect)));
  if (rows < 16) throw std::invalid_argument("croppedCamera: fewer than 16 rows would be left");
  return {(camera.height - rows) / 2, rows};
}

}  // namespace

PinholeCamera croppedCamera(const PinholeCamera& camera, double aspect) {
  if (camera.unregistered_depth)
    throw std::invalid_argument("croppedCamera: the camera has an unregistered depth camera; crop before making it");
  const auto [top, rows] = croppedRows(camera, aspect);
  PinholeCamera cropped = camera;
  cropped.height = rows;
  cropped.cy -= top;
  return cropped;
}

cv::Mat cropImage(const cv::Mat& image, const PinholeCamera& camera, double aspect) {
  if (image.cols != camera.width || image.rows != camera.height)
    throw std::invalid_argument("cropImage: image is " + std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                                ", the camera " + std::to_string(camera.width) + "x" + std::to_string(camera.height));
  const auto [top, rows] = croppedRows(camera, aspect);
  return image.rowRange(top, top + rows).clone();
}

PinholeCamera depthResizedCamera(const PinholeCamera& camera, double scale) {
  if (!(scale > 0.0) || !std::isfinite(scale))
    throw std::invalid_argument("depthResizedCamera: scale must be > 0, got " + std::to_string(scale));
  PinholeCamera resized = camera;
  if (!resized.unregistered_depth)  // registered depth: a depth camera where the colour camera is, undistorted
    resized.unregistered_depth = DepthCamera{camera.fx, camera.fy, camera.cx, camera.cy, {}, {}};
  DepthCamera& depth = *resized.unregistered_depth;
  const cv::Size old_size = camera.depthImageSize();
  depth.width = static_cast<int>(std::lround(old_size.width * scale));
  depth.height = static_cast<int>(std::lround(old_size.height * scale));
  if (depth.width < 16 || depth.height < 16)
    throw std::invalid_argument("depthResizedCamera: " + std::to_string(old_size.width) + "x" +
                                std::to_string(old_size.height) + " times " + std::to_string(scale) +
                                " is smaller than 16x16 pixels");
  depth = depth.resampled(static_cast<double>(depth.width) / old_size.width,
                          static_cast<double>(depth.height) / old_size.height);
  return resized;
}

cv::Mat depthResizedImage(const cv::Mat& depth, const PinholeCamera& camera, double scale) {
  const cv::Size old_size = camera.depthImageSize();
  if (depth.type() != CV_32F || depth.size() != old_size)
    throw std::invalid_argument("depthResizedImage: depth must be CV_32F of the depth camera's " +
                                std::to_string(old_size.width) + "x" + std::to_string(old_size.height) + ", found " +
                                std::to_string(depth.cols) + "x" + std::to_string(depth.rows));
  const PinholeCamera resized = depthResizedCamera(camera, scale);
  // Registered depth is indexed by the raw (distorted) colour pixels: first as the undistorted depth camera at the
  // colour camera's place sees it.
  const cv::Mat undistorted = !camera.unregistered_depth && camera.hasDistortion()
                                  ? unregisteredDepth(depth, camera, Eigen::Isometry3d::Identity())
                                  : depth;
  cv::Mat out;
  cv::resize(undistorted, out, resized.depthImageSize(), 0.0, 0.0, cv::INTER_NEAREST);
  return out;
}

cv::Mat resizeImage(const cv::Mat& image, const PinholeCamera& camera, double scale, int interpolation) {
  if (image.empty()) throw std::invalid_argument("resizeImage: empty image");
  if (image.cols != camera.width || image.rows != camera.height)
    throw std::invalid_argument("resizeImage: image is " + std::to_string(image.cols) + "x" +
                                std::to_string(image.rows) + ", the camera " + std::to_string(camera.width) + "x" +
                                std::to_string(camera.height));
  const PinholeCamera resized = resizedCamera(camera, scale);
  // Area averaging only shrinks; enlarging with it would be nearest-neighbour blocks.
  if (interpolation == cv::INTER_AREA && scale > 1.0) interpolation = cv::INTER_LINEAR;
  cv::Mat out;
  cv::resize(image, out, cv::Size(resized.width, resized.height), 0.0, 0.0, interpolation);
  return out;
}

namespace {
/// Every pixel of the camera's (raw) image, row by row, undistorted (the pixel itself without distortion).
std::vector<cv::Point2f> undistortedPixels(const PinholeCamera& camera) {
  std::vector<cv::Point2f> pixels;
  pixels.reserve(static_cast<std::size_t>(camera.width) * static_cast<std::size_t>(camera.height));
  for (int v = 0; v < camera.height; ++v)
    for (int u = 0; u < camera.width; ++u) pixels.emplace_back(static_cast<float>(u), static_cast<float>(v));
  if (!camera.hasDistortion()) return pixels;
  std::vector<cv::Point2f> undistorted;
  cv::undistortPoints(pixels, undistorted, camera.cameraMatrix(), camera.distortionCoefficients(), cv::noArray(),
                      camera.cameraMatrix());
  return undistorted;
}
}  // namespace

cv::Mat unregisteredDepth(const cv::Mat& depth, const PinholeCamera& camera, const Eigen::Isometry3d& depth_in_color) {
  if (depth.type() != CV_32F) throw std::invalid_argument("unregisteredDepth: depth must be CV_32F metres");
  if (depth.cols != camera.width || depth.rows != camera.height)
    throw std::invalid_argument("unregisteredDepth: depth is " + std::to_string(depth.cols) + "x" +
                                std::to_string(depth.rows) + ", the camera " + std::to_string(camera.width) + "x" +
                                std::to_string(camera.height));
  const Eigen::Isometry3d color_to_depth = depth_in_color.inverse();
  // Depth pixel (u, v) is colour pixel (u, v), a raw (distorted) one: its ray is that of the undistorted pixel.
  const std::vector<cv::Point2f> rays = undistortedPixels(camera);
  PinholeCamera depth_camera = camera;  // the depth camera: the colour camera's intrinsics, no distortion
  depth_camera.distortion = {};
  cv::Mat splatted(depth.size(), CV_32F, cv::Scalar(0.0f));
  for (int v = 0; v < depth.rows; ++v)
    for (int u = 0; u < depth.cols; ++u) {
      const float z = depth.at<float>(v, u);
      if (!(z > 0.0f) || !std::isfinite(z)) continue;
      const cv::Point2f& ray =
          rays[static_cast<std::size_t>(v) * static_cast<std::size_t>(depth.cols) + static_cast<std::size_t>(u)];
      const Eigen::Vector3d in_depth = color_to_depth * depth_camera.backProject(ray.x, ray.y, z);
      if (in_depth.z() <= 0.0) continue;
      const Eigen::Vector2d pixel = depth_camera.project(in_depth);
      const int tu = static_cast<int>(std::lround(pixel.x())), tv = static_cast<int>(std::lround(pixel.y()));
      if (tu < 0 || tv < 0 || tu >= depth.cols || tv >= depth.rows) continue;
      float& target = splatted.at<float>(tv, tu);
      const float moved = static_cast<float>(in_depth.z());
      if (target == 0.0f || moved < target) target = moved;  // the nearer surface hides the farther
    }
  // Resampling leaves one-pixel cracks; an occlusion edge uncovers background,
  // so a crack takes its farthest neighbour.
  cv::Mat farthest;
  cv::dilate(splatted, farthest, cv::Mat());
  cv::Mat filled = splatted.clone();
  for (int v = 1; v + 1 < depth.rows; ++v)
    for (int u = 1; u + 1 < depth.cols; ++u)
      if (splatted.at<float>(v, u) == 0.0f && depth.at<float>(v, u) > 0.0f)
        filled.at<float>(v, u) = farthest.at<float>(v, u);
  return filled;
}

}  // namespace weighted_icp::simulation
