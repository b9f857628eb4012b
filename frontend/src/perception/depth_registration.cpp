// Registration of an unregistered sensor's depth to its colour camera (see depth_registration.h).
#include "weighted_icp/frontend/perception/depth_registration.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>
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

/// Writes one row's projections into `registered` (infinity where nothing landed yet): each measured depth pixel
/// onto the 2 x 2 colour pixels around where it lands (as registerDepth's depth dilation: a depth image seen from a
/// little aside leaves no one-pixel cracks), the nearer depth kept where two surfaces land on one pixel.
/// @param depth the row's depths (0, NaN or infinite: unmeasured)
/// @param target_u,target_v,target_z where each lands (RowProjection)
/// @param registered CV_32F of the colour image's size
void splatRow(const float* depth, const float* target_u, const float* target_v, const float* target_z,
              cv::Mat& registered) {
  const float width = static_cast<float>(registered.cols), height = static_cast<float>(registered.rows);
  const float unseen = std::numeric_limits<float>::infinity();
  for (int u = 0; u < registered.cols; ++u) {
    const float z = depth[u], pz = target_z[u], uc = target_u[u], vc = target_v[u];
    // Unmeasured, behind the colour camera, or outside its image.
    if (!(z > 0.0f) || !(z < unseen) || !(pz > 0.0f)) continue;
    if (!(uc > -1.0f && vc > -1.0f && uc < width && vc < height)) continue;
    const int u0 = static_cast<int>(uc + 1.0f) - 1, v0 = static_cast<int>(vc + 1.0f) - 1;  // floor, as uc, vc > -1
    if (u0 >= 0 && v0 >= 0 && u0 + 1 < registered.cols && v0 + 1 < registered.rows) {
      float* top = registered.ptr<float>(v0) + u0;
      float* bottom = registered.ptr<float>(v0 + 1) + u0;
      top[0] = std::min(top[0], pz);
      top[1] = std::min(top[1], pz);
      bottom[0] = std::min(bottom[0], pz);
      bottom[1] = std::min(bottom[1], pz);
      continue;
    }
    for (int tv = v0; tv <= v0 + 1; ++tv) {
      if (tv < 0 || tv >= registered.rows) continue;
      float* target = registered.ptr<float>(tv);
      for (int tu = u0; tu <= u0 + 1; ++tu)
        if (tu >= 0 && tu < registered.cols) target[tu] = std::min(target[tu], pz);
    }
  }
}

/// Throws std::invalid_argument unless the camera has a depth camera and the depth is CV_32F of its size.
void checkInputs(const char* function, const cv::Mat& depth, const PinholeCamera& camera) {
  if (!camera.unregistered_depth)
    throw std::invalid_argument(std::string(function) + ": the camera has no unregistered depth camera");
  if (depth.type() != CV_32F || depth.cols != camera.width || depth.rows != camera.height)
    throw std::invalid_argument(std::string(function) + ": depth must be CV_32F metres of " +
                                std::to_string(camera.width) + "x" + std::to_string(camera.height) + ", found " +
                                std::to_string(depth.cols) + "x" + std::to_string(depth.rows));
}

}  // namespace

cv::Mat registerDepthWithOpenCv(const cv::Mat& depth, const PinholeCamera& camera) {
  checkInputs("registerDepthWithOpenCv", depth, camera);
  const DepthCamera& sensor = *camera.unregistered_depth;
  const cv::Matx33f depth_matrix(static_cast<float>(sensor.fx), 0.0f, static_cast<float>(sensor.cx), 0.0f,
                                 static_cast<float>(sensor.fy), static_cast<float>(sensor.cy), 0.0f, 0.0f, 1.0f);
  cv::Matx33f color_matrix;
  cv::Mat(camera.cameraMatrix()).convertTo(color_matrix, CV_32F);
  const Eigen::Matrix4d pose = sensor.depthInColor().matrix();
  cv::Matx44f depth_to_color;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) depth_to_color(r, c) = static_cast<float>(pose(r, c));
  cv::Mat coefficients, measured = depth.clone(), registered;
  camera.distortionCoefficients().convertTo(coefficients, CV_32F);
  measured.setTo(std::numeric_limits<float>::quiet_NaN(), ~(depth > 0.0f));  // a float image's "no depth"
  cv::rgbd::registerDepth(depth_matrix, color_matrix, coefficients, depth_to_color, measured, depth.size(), registered,
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
  const float cx = static_cast<float>(camera.cx), cy = static_cast<float>(camera.cy);
  const float unseen = std::numeric_limits<float>::infinity();
  cv::Mat registered(depth.size(), CV_32F);
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
    splatRow(row, target_u.data(), target_v.data(), target_z.data(), registered);
  }
  for (float *value = registered.ptr<float>(0), *end = value + registered.total(); value != end; ++value)
    if (*value == unseen) *value = 0.0f;
  return registered;
}

}  // namespace weighted_icp::frontend
