// Registration of an unregistered sensor's depth to its colour camera (see depth_registration.h).
#include "weighted_icp/frontend/perception/depth_registration.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>
#include <opencv2/rgbd.hpp>

namespace weighted_icp::frontend {

namespace {

/// The colour camera's distortion (OpenCV's k1 k2 p1 p2 k3), applied to normalised coordinates.
struct Distortion {
  float k1, k2, p1, p2, k3;
  explicit Distortion(const PinholeCamera& camera)
      : k1(static_cast<float>(camera.distortion[0])),
        k2(static_cast<float>(camera.distortion[1])),
        p1(static_cast<float>(camera.distortion[2])),
        p2(static_cast<float>(camera.distortion[3])),
        k3(static_cast<float>(camera.distortion[4])) {}
  void apply(float& x, float& y) const {
    const float r2 = x * x + y * y;
    const float radial = 1.0f + r2 * (k1 + r2 * (k2 + r2 * k3));
    const float xd = x * radial + 2.0f * p1 * x * y + p2 * (r2 + 2.0f * x * x);
    const float yd = y * radial + p1 * (r2 + 2.0f * y * y) + 2.0f * p2 * x * y;
    x = xd;
    y = yd;
  }
};

/// Where the depth pixels of one row land in the colour image: pixel (target_u, target_v) at depth target_z. No
/// branch and no aliasing, so that the compiler vectorises it (the scatter that follows cannot be).
struct RowProjection {
  const float* ray_x;  // per column
  Eigen::Vector3f column_x, row_direction, translation;
  float fx, fy, cx, cy;

  template <bool kDistorted>
  void project(const float* __restrict depth, std::size_t columns, const Distortion& distortion,
               float* __restrict target_u, float* __restrict target_v, float* __restrict target_z) const {
    for (std::size_t u = 0; u < columns; ++u) {
      const float z = depth[u];
      const float px = z * (ray_x[u] * column_x.x() + row_direction.x()) + translation.x();
      const float py = z * (ray_x[u] * column_x.y() + row_direction.y()) + translation.y();
      const float pz = z * (ray_x[u] * column_x.z() + row_direction.z()) + translation.z();
      const float inverse_z = 1.0f / pz;
      float x = px * inverse_z, y = py * inverse_z;
      if constexpr (kDistorted) distortion.apply(x, y);
      target_u[u] = fx * x + cx;
      target_v[u] = fy * y + cy;
      target_z[u] = pz;
    }
  }
};

/// How many colour pixels a depth pixel covers along each axis: at least 2 x 2 (as registerDepth's depth dilation:
/// a depth image seen from a little aside leaves no one-pixel cracks), and more where the depth camera's pixels are
/// larger than the colour camera's (a lower-resolution depth sensor): neighbouring depth pixels land `scale` colour
/// pixels apart, so a footprint of at least scale + 0.5 pixels leaves no crack between them.
struct Footprint {
  /// A depth camera of a 32nd of the colour camera's resolution is no sensor: a bound on the work per pixel.
  static constexpr int kMaxSide = 32;
  int columns = 2, rows = 2;
  /// The footprint's first column is floor(u - shift_u) for a depth pixel landing at column u (2 pixels: floor(u)).
  float shift_u = 0.0f, shift_v = 0.0f;

  Footprint(const PinholeCamera& colour, const DepthCamera& sensor)
      : columns(std::clamp(static_cast<int>(std::ceil(colour.fx / sensor.fx + 0.5)), 2, kMaxSide)),
        rows(std::clamp(static_cast<int>(std::ceil(colour.fy / sensor.fy + 0.5)), 2, kMaxSide)),
        shift_u(0.5f * static_cast<float>(columns - 2)),
        shift_v(0.5f * static_cast<float>(rows - 2)) {}
};

/// Writes one row's projections into `registered` (infinity where nothing landed yet): each measured depth pixel
/// onto the colour pixels of its footprint around where it lands, the nearer depth kept where two surfaces land on
/// one pixel.
/// @param depth the row's depths (0, NaN or infinite: unmeasured), `columns` of them
/// @param target_u,target_v,target_z where each lands (RowProjection), the pixel less the footprint's shift
/// @param footprint the colour pixels each covers
/// @param registered CV_32F of the colour image's size
void splatRow(const float* depth, std::size_t columns, const float* target_u, const float* target_v,
              const float* target_z, const Footprint& footprint, cv::Mat& registered) {
  const float width = static_cast<float>(registered.cols), height = static_cast<float>(registered.rows);
  const float unseen = std::numeric_limits<float>::infinity();
  const bool two_by_two = footprint.columns == 2 && footprint.rows == 2;
  const int reach_u = footprint.columns - 1, reach_v = footprint.rows - 1;
  const float min_u = static_cast<float>(-reach_u), min_v = static_cast<float>(-reach_v);
  for (std::size_t u = 0; u < columns; ++u) {
    const float z = depth[u], pz = target_z[u], uc = target_u[u], vc = target_v[u];
    // Unmeasured, behind the colour camera, or its footprint outside the colour image.
    if (!(z > 0.0f) || !(z < unseen) || !(pz > 0.0f)) continue;
    if (!(uc > min_u && vc > min_v && uc < width && vc < height)) continue;
    const int u0 = static_cast<int>(uc - min_u) - reach_u;  // floor, as uc + reach_u > 0
    const int v0 = static_cast<int>(vc - min_v) - reach_v;
    if (two_by_two && u0 >= 0 && v0 >= 0 && u0 + 1 < registered.cols && v0 + 1 < registered.rows) {
      float* top = registered.ptr<float>(v0) + u0;
      float* bottom = registered.ptr<float>(v0 + 1) + u0;
      top[0] = std::min(top[0], pz);
      top[1] = std::min(top[1], pz);
      bottom[0] = std::min(bottom[0], pz);
      bottom[1] = std::min(bottom[1], pz);
      continue;
    }
    for (int tv = std::max(v0, 0); tv < std::min(v0 + footprint.rows, registered.rows); ++tv) {
      float* target = registered.ptr<float>(tv);
      for (int tu = std::max(u0, 0); tu < std::min(u0 + footprint.columns, registered.cols); ++tu)
        target[tu] = std::min(target[tu], pz);
    }
  }
}

/// Throws std::invalid_argument unless the camera has a depth camera and the depth is CV_32F of its image size.
void checkInputs(const char* function, const cv::Mat& depth, const PinholeCamera& camera) {
  if (!camera.unregistered_depth)
    throw std::invalid_argument(std::string(function) + ": the camera has no unregistered depth camera");
  const cv::Size size = camera.depthImageSize();
  if (depth.type() != CV_32F || depth.size() != size)
    throw std::invalid_argument(std::string(function) + ": depth must be CV_32F metres of the depth camera's " +
                                std::to_string(size.width) + "x" + std::to_string(size.height) + ", found " +
                                std::to_string(depth.cols) + "x" + std::to_string(depth.rows) +
                                (depth.type() == CV_32F ? "" : " not of CV_32F"));
}

}  // namespace

cv::Mat registerDepthWithOpenCv(const cv::Mat& depth, const PinholeCamera& camera) {
  checkInputs("registerDepthWithOpenCv", depth, camera);
  // registerDepth reads the depth image over the output's size (OpenCV 4.6: a smaller one is read out of bounds, a
  // larger one only in part): a depth image of another size is first resized to the colour image's (nearest), its
  // intrinsics with it.
  const cv::Size colour_size(camera.width, camera.height);
  const bool resample = depth.size() != colour_size;
  const DepthCamera sensor = resample
                                 ? camera.unregistered_depth->resampled(static_cast<double>(camera.width) / depth.cols,
                                                                        static_cast<double>(camera.height) / depth.rows)
                                 : *camera.unregistered_depth;
  cv::Mat measured;
  if (resample)
    cv::resize(depth, measured, colour_size, 0.0, 0.0, cv::INTER_NEAREST);
  else
    measured = depth.clone();
  const cv::Matx33f depth_matrix(static_cast<float>(sensor.fx), 0.0f, static_cast<float>(sensor.cx), 0.0f,
                                 static_cast<float>(sensor.fy), static_cast<float>(sensor.cy), 0.0f, 0.0f, 1.0f);
  cv::Matx33f color_matrix;
  cv::Mat(camera.cameraMatrix()).convertTo(color_matrix, CV_32F);
  const Eigen::Matrix4d pose = sensor.depthInColor().matrix();
  cv::Matx44f depth_to_color;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) depth_to_color(r, c) = static_cast<float>(pose(r, c));
  cv::Mat coefficients, registered;
  camera.distortionCoefficients().convertTo(coefficients, CV_32F);
  measured.setTo(std::numeric_limits<float>::quiet_NaN(), ~(measured > 0.0f));  // a float image's "no depth"
  cv::rgbd::registerDepth(depth_matrix, color_matrix, coefficients, depth_to_color, measured, colour_size, registered,
                          true);
  registered.setTo(0.0f, registered != registered);
  return registered;
}

cv::Mat registerDepthToColor(const cv::Mat& depth, const PinholeCamera& camera) {
  checkInputs("registerDepthToColor", depth, camera);
  // By hand rather than cv::rgbd::registerDepth (registerDepthWithOpenCv), which gives the same depths (tested) in
  // 16.8 ms against 1.9 ms on a frame of fr1 (8.2 against 1.5 ms without lens distortion, fr3):
  // wicp_benchmark_matching --benchmark_filter=Register.
  const DepthCamera& sensor = *camera.unregistered_depth;
  const Eigen::Isometry3f depth_to_color = sensor.depthInColor().cast<float>();
  const Eigen::Matrix3f rotation = depth_to_color.linear();
  const Eigen::Vector3f translation = depth_to_color.translation();
  // A depth pixel's point in the colour camera is z * (R ray(u, v)) + t, and R ray(u, v) = x_u R_0 + (y_v R_1 + R_2):
  // one column of R per pixel, the rest once per row.
  std::vector<float> ray_x(static_cast<std::size_t>(depth.cols));
  for (int u = 0; u < depth.cols; ++u)
    ray_x[static_cast<std::size_t>(u)] = static_cast<float>((u - sensor.cx) / sensor.fx);
  const Eigen::Vector3f column_x = rotation.col(0);
  const bool distorted = camera.hasDistortion();
  const Distortion distortion(camera);
  const float fx = static_cast<float>(camera.fx), fy = static_cast<float>(camera.fy);
  // The footprint's shift folded into the principal point: the projection gives its first pixel's corner.
  const Footprint footprint(camera, sensor);
  const float cx = static_cast<float>(camera.cx) - footprint.shift_u;
  const float cy = static_cast<float>(camera.cy) - footprint.shift_v;
  const float unseen = std::numeric_limits<float>::infinity();
  cv::Mat registered(camera.height, camera.width, CV_32F);
  std::fill(registered.ptr<float>(0), registered.ptr<float>(0) + registered.total(), unseen);  // continuous, new
  // Per row, first every pixel's projection (no branch: the compiler vectorises it), then the scatter.
  const std::size_t columns = static_cast<std::size_t>(depth.cols);
  std::vector<float> target_u(columns), target_v(columns), target_z(columns);
  for (int v = 0; v < depth.rows; ++v) {
    const float* row = depth.ptr<float>(v);
    const Eigen::Vector3f row_direction =
        static_cast<float>((v - sensor.cy) / sensor.fy) * rotation.col(1) + rotation.col(2);
    const RowProjection projection{ray_x.data(), column_x, row_direction, translation, fx, fy, cx, cy};
    if (distorted)
      projection.project<true>(row, columns, distortion, target_u.data(), target_v.data(), target_z.data());
    else
      projection.project<false>(row, columns, distortion, target_u.data(), target_v.data(), target_z.data());
    splatRow(row, columns, target_u.data(), target_v.data(), target_z.data(), footprint, registered);
  }
  for (float *value = registered.ptr<float>(0), *end = value + registered.total(); value != end; ++value)
    if (*value == unseen) *value = 0.0f;
  return registered;
}

}  // namespace weighted_icp::frontend
