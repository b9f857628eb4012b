// Which pixels can see a box (see raycasting.h); the per-ray queries are
// inline in the header, as the renderer runs them for every pixel.

#include "raycasting.h"

namespace weighted_icp::simulation {

cv::Rect pixelBounds(const RayBox& box, const Eigen::Isometry3d& camera_to_world, const PinholeCamera& camera) {
  const cv::Rect image(0, 0, camera.width, camera.height);
  const Eigen::Isometry3d world_to_camera = camera_to_world.inverse();
  double min_u = std::numeric_limits<double>::infinity(), min_v = min_u, max_u = -min_u, max_v = -min_u;
  int corners_behind = 0;
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d offset(corner & 1 ? box.upper().x() : box.lower().x(),
                                 corner & 2 ? box.upper().y() : box.lower().y(),
                                 corner & 4 ? box.upper().z() : box.lower().z());
    const Eigen::Vector3d in_camera = world_to_camera * (box.origin() + box.toWorld(offset));
    if (in_camera.z() <= 1e-3) {
      ++corners_behind;
      continue;
    }
    const Eigen::Vector2d pixel = camera.project(in_camera);
    min_u = std::min(min_u, pixel.x()), max_u = std::max(max_u, pixel.x());
    min_v = std::min(min_v, pixel.y()), max_v = std::max(max_v, pixel.y());
  }
  // All behind: unseen. Some behind: its outline is unbounded, test every pixel.
  if (corners_behind == 8) return cv::Rect();
  if (corners_behind > 0) return image;
  const cv::Rect bounds(cv::Point(static_cast<int>(std::floor(min_u)) - 1, static_cast<int>(std::floor(min_v)) - 1),
                        cv::Point(static_cast<int>(std::ceil(max_u)) + 2, static_cast<int>(std::ceil(max_v)) + 2));
  return bounds & image;
}

}  // namespace weighted_icp::simulation
