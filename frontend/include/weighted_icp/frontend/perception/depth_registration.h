#pragma once
// Depth images of a sensor whose depth camera is not its colour camera (raw
// Kinect or Astra streams), moved into the colour camera's pixels, so that a
// feature's depth is read where the feature is.

#include <opencv2/core.hpp>

#include "weighted_icp/core/camera.h"

namespace weighted_icp::frontend {

/// @brief The depth image as the colour camera would see it (cv::rgbd::registerDepth): every depth pixel is
/// back-projected with the depth camera's intrinsics, moved by its pose in the colour camera's frame and projected
/// with the colour camera's intrinsics and distortion (the raw colour pixels features are detected in); where two
/// land on one pixel the nearer is kept, one-pixel cracks are filled, pixels nothing lands on have no depth (0).
/// A depth camera of a lower resolution than the colour camera's (an Azure Kinect's, ScanNet's) covers each colour
/// pixel: every depth pixel is drawn over as many colour pixels as it spans (the focal lengths' ratio, + 0.5).
/// @param depth CV_32F metres from the depth camera, 0 or NaN where unmeasured, of the depth camera's size
/// (PinholeCamera::depthImageSize)
/// @param camera the colour camera, with its unregistered_depth set; else std::invalid_argument, as for a depth
/// image of another type or size
/// @return CV_32F metres of the colour image's size (camera.width x camera.height), 0 where unmeasured
cv::Mat registerDepthToColor(const cv::Mat& depth, const PinholeCamera& camera);

/// @brief The same registration by OpenCV's cv::rgbd::registerDepth (with its depth dilation), for comparison: the
/// same depths within a few millimetres, 5 to 9 times slower (wicp_benchmark_matching --benchmark_filter=Register).
/// registerDepth reads the depth image over the output's size (OpenCV 4.6 reads a smaller one out of bounds): a
/// depth camera of another resolution has its image resized to the colour image's first (nearest), as OpenCV's
/// user must.
/// @param depth as for registerDepthToColor
/// @param camera as for registerDepthToColor
cv::Mat registerDepthWithOpenCv(const cv::Mat& depth, const PinholeCamera& camera);

}  // namespace weighted_icp::frontend
