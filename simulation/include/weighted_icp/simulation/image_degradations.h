#pragma once
// Image-level simulations of other sensors and conditions, applied to real or
// synthetic RGB-D frames: motion blur, low light, another exposure, sensor
// noise, another focal length (zoom about the principal point), resolution or
// aspect ratio, and depth that is not registered to the colour image.
// sequence_variants.h applies them to whole sequences.

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "weighted_icp/core/camera.h"

namespace weighted_icp::simulation {

/// @brief Linear motion blur: the image averaged along a segment, as an
/// exposure during which the image moved `length_px` at `angle_deg`.
/// @param image 8-bit, 1 to 4 channels
/// @param length_px segment length in pixels (>= 1; 1 returns a copy)
/// @param angle_deg direction of the motion in the image, degrees from +x
cv::Mat motionBlur(const cv::Mat& image, double length_px, double angle_deg);

/// @brief Adds zero-mean Gaussian noise of `sigma` grey levels, saturating.
/// @param image 8-bit, 1 to 4 channels
/// @param sigma standard deviation in grey levels (>= 0)
/// @param rng the source of the noise (seeded by the caller for determinism)
cv::Mat addGaussianNoise(const cv::Mat& image, double sigma, cv::RNG& rng);

/// @brief Depth as a noisier sensor measures it (a stereo depth camera: its error grows with the square of the
/// distance): z + coefficient z^2 n, n a unit-variance Gaussian field, smoothed over `correlation_px` (a sensor's
/// errors come in patches, not per pixel; 0: independent pixels) and scaled back to unit variance. Pixels without
/// a reading (0, not finite) stay 0; a reading pushed to 0 or below becomes 0 (no reading).
/// @param depth CV_32F metres
/// @param coefficient metres per square metre (>= 0): 0.0015 is about a Kinect v1's, 0.01 a consumer stereo camera's
/// @param correlation_px the smoothing Gaussian's sigma in pixels (>= 0)
/// @param rng the source of the noise
cv::Mat noisyDepth(const cv::Mat& depth, double coefficient, double correlation_px, cv::RNG& rng);

/// @brief A low-light exposure: value = 255 gain (value / 255)^gamma, then
/// read noise of `noise_sigma` grey levels (a dark image's noise is relatively
/// larger, which is what makes low light hard).
/// @param image 8-bit, 1 to 4 channels
/// @param gain in (0, 1]
/// @param gamma > 0 (above 1 crushes the shadows)
/// @param noise_sigma grey levels, after the gain
/// @param rng the source of the noise
cv::Mat lowLight(const cv::Mat& image, double gain, double gamma, double noise_sigma, cv::RNG& rng);

/// @brief Another exposure of the same scene: the light times 2^stops, in linear light (8-bit values taken as
/// gamma 2.2), saturating at 255, as a camera's auto exposure or gain changes it from frame to frame (a brighter
/// exposure also clips the highlights, a darker one crushes the shadows into fewer grey levels).
/// @param image 8-bit, 1 to 4 channels
/// @param stops the change in stops, in [-8, 8] (0: a copy; 1: twice the light)
cv::Mat changeExposure(const cv::Mat& image, double stops);

/// @brief The camera of zoomImage: focal lengths times `scale`, the principal
/// point, distortion (in normalised coordinates, unchanged by a zoom about the
/// principal point), size and depth factor unchanged. An unregistered depth camera's image is zoomed about the
/// colour camera's principal point too, so it must be of the colour image's size (std::invalid_argument otherwise).
/// @param camera the original camera
/// @param scale new focal length / old (> 0)
PinholeCamera zoomedCamera(const PinholeCamera& camera, double scale);

/// @brief The image a camera with `scale` times the focal length would have
/// seen from the same place: a zoom about the principal point, same size.
/// Pixels outside the original (scale < 1) are 0, which is "no reading" for depth.
/// @param image colour or depth image of `camera`'s size
/// @param camera its camera (the principal point is the zoom's centre)
/// @param scale new focal length / old (> 0)
/// @param interpolation cv::INTER_LINEAR for colour, cv::INTER_NEAREST for
///        depth (never mix a foreground and a background depth)
cv::Mat zoomImage(const cv::Mat& image, const PinholeCamera& camera, double scale, int interpolation);

/// @brief The camera of resizeImage: a sensor of another resolution with the same field of view. Size times `scale`
/// (rounded), focal lengths times each axis' exact ratio s (new size / old), the principal point moved with the pixel
/// grid ((c + 0.5) s - 0.5), distortion (normalised coordinates) and depth factor unchanged; an unregistered depth
/// camera is resized alike.
/// @param camera the original camera
/// @param scale new width / old (> 0); the new size must be at least 16 x 16 pixels
PinholeCamera resizedCamera(const PinholeCamera& camera, double scale);

/// @brief The image at resizedCamera's size.
/// @param image colour or depth image of `camera`'s size
/// @param camera its camera
/// @param scale new width / old (> 0)
/// @param interpolation cv::INTER_AREA for colour (each new pixel averages the old ones it covers; bilinear when
///        enlarging), cv::INTER_NEAREST for depth (never mix a foreground and a background depth)
cv::Mat resizeImage(const cv::Mat& image, const PinholeCamera& camera, double scale, int interpolation);

/// @brief The camera of cropImage: a sensor of another aspect ratio with the same pixels and lens, its image the
/// middle rows of the original (a 16:9 sensor's beside a 4:3 one's). Width, focal lengths, cx and distortion kept;
/// height lround(width / aspect), cy moved up by the rows cut above. A camera with an unregistered depth camera is
/// refused (its depth image would need a crop of its own): crop before making it.
/// @param camera the original camera
/// @param aspect width / new height, in [width / height, 4]; the new height must be at least 16 pixels
PinholeCamera croppedCamera(const PinholeCamera& camera, double aspect);

/// @brief The image at croppedCamera's size: its middle rows.
/// @param image colour or depth image of `camera`'s size
/// @param camera its camera
/// @param aspect width / new height, as croppedCamera
cv::Mat cropImage(const cv::Mat& image, const PinholeCamera& camera, double aspect);

/// @brief The camera of a depth sensor of another resolution than the colour camera's (an Azure Kinect's, ScanNet's):
/// the depth camera's images resized by `scale` (same field of view, its intrinsics as resizedCamera scales them),
/// the colour camera unchanged. A camera with registered depth first gets a depth camera where the colour camera
/// is: its intrinsics without its distortion, no offset.
/// @param camera the original camera
/// @param scale new depth width / old (> 0); the new depth size must be at least 16 x 16 pixels
PinholeCamera depthResizedCamera(const PinholeCamera& camera, double scale);

/// @brief The depth image at depthResizedCamera's depth size (nearest: never mix a foreground and a background
/// depth). Registered depth of a camera with lens distortion is first re-sampled as the undistorted depth camera
/// sees it (unregisteredDepth with no offset).
/// @param depth CV_32F metres of `camera`'s depth size (PinholeCamera::depthImageSize)
/// @param camera its camera
/// @param scale new depth width / old (> 0)
cv::Mat depthResizedImage(const cv::Mat& depth, const PinholeCamera& camera, double scale);

/// @brief Depth as an unregistered sensor delivers it: seen from a depth
/// camera at `depth_in_color` (its pose in the colour camera's frame) with the
/// colour camera's intrinsics and no lens distortion, but indexed as if it were
/// the colour camera's. Each (raw, distorted) colour pixel is lifted along its
/// undistorted ray with its depth, moved into the depth camera and splatted
/// (nearest pixel, nearest depth wins); one-pixel cracks of the resampling are
/// filled with the farther neighbour. frontend::registerDepthToColor, given
/// that depth camera, undoes it (until 2026-11-26 the colour pixel's ray
/// ignored the distortion, which no registration of a real sensor would undo).
/// @param depth CV_32F metres (0 or NaN: no reading), `camera`'s size
/// @param camera the colour camera's intrinsics
/// @param depth_in_color the depth camera's pose in the colour camera's frame
cv::Mat unregisteredDepth(const cv::Mat& depth, const PinholeCamera& camera, const Eigen::Isometry3d& depth_in_color);

}  // namespace weighted_icp::simulation
