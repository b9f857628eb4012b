// The synthetic SLAM session (see session.h): landmarks placed on the room's
// surfaces, a camera arc, the observations a feature tracker would make (ray
// cast against the furniture for occlusion) and the map a drifting odometry
// builds from them.

#include "weighted_icp/simulation/session.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>

#include "random_source.h"
#include "raycasting.h"

namespace weighted_icp::simulation {

namespace {

constexpr double kDegree = M_PI / 180.0;

enum Stream : std::uint32_t { kLayoutStream = 1, kDriftStream = 2, kObservationStream = 3 };

/// A textured planar patch: corner + s * edge_a + t * edge_b, s, t in [0, 1].
struct Rectangle {
  Eigen::Vector3d corner, edge_a, edge_b;
  Eigen::Vector3d normal;  // the side features are seen from
  int block = -1;          // index of the block it is a face of; -1 for the room's own
  double area() const { return edge_a.cross(edge_b).norm(); }
};

struct Room {
  std::vector<Rectangle> surfaces;
  /// Furniture: axis-aligned boxes standing in the room.
  std::vector<RayBox> blocks;

  /// The five upper faces of a block standing on the floor or on another
  /// block. Faces turned to a wall are kept: no camera ever faces them, so
  /// their landmarks go unobserved and are dropped.
  void addBlock(const Eigen::Vector3d& min, const Eigen::Vector3d& max) {
    const int index = static_cast<int>(blocks.size());
    blocks.push_back(RayBox::fromCorners(min, max));
    const Eigen::Vector3d size = max - min;
    const Eigen::Vector3d dx(size.x(), 0, 0), dy(0, size.y(), 0), dz(0, 0, size.z());
    surfaces.push_back({Eigen::Vector3d(min.x(), min.y(), max.z()), dx, dy, Eigen::Vector3d::UnitZ(), index});
    surfaces.push_back({min, dx, dz, -Eigen::Vector3d::UnitY(), index});
    surfaces.push_back({Eigen::Vector3d(min.x(), max.y(), min.z()), dx, dz, Eigen::Vector3d::UnitY(), index});
    surfaces.push_back({min, dy, dz, -Eigen::Vector3d::UnitX(), index});
    surfaces.push_back({Eigen::Vector3d(max.x(), min.y(), min.z()), dy, dz, Eigen::Vector3d::UnitX(), index});
  }
  /// A point of `surface` that another block covers (floor under a box, wall
  /// behind the desk) is not on any visible surface.
  bool covered(const Eigen::Vector3d& point, const Rectangle& surface) const {
    for (std::size_t b = 0; b < blocks.size(); ++b)
      if (static_cast<int>(b) != surface.block && blocks[b].contains(point)) return true;
    return false;
  }
  bool occluded(const Eigen::Vector3d& camera_centre, const Eigen::Vector3d& point) const {
    for (const RayBox& block : blocks)
      if (block.blocksSegment(camera_centre, point)) return true;
    return false;
  }
};

Room makeRoom(const Eigen::Vector3d& room_size) {
  const double hx = room_size.x() / 2, hy = room_size.y() / 2, height = room_size.z();
  const Eigen::Vector3d along_x(room_size.x(), 0, 0), along_y(0, room_size.y(), 0), up(0, 0, height);
  Room room;
  room.surfaces.push_back({Eigen::Vector3d(-hx, -hy, 0), along_x, along_y, Eigen::Vector3d::UnitZ()});  // floor
  room.surfaces.push_back({Eigen::Vector3d(-hx, -hy, 0), along_y, up, Eigen::Vector3d::UnitX()});
  room.surfaces.push_back({Eigen::Vector3d(hx, -hy, 0), along_y, up, -Eigen::Vector3d::UnitX()});
  room.surfaces.push_back({Eigen::Vector3d(-hx, -hy, 0), along_x, up, Eigen::Vector3d::UnitY()});
  room.surfaces.push_back({Eigen::Vector3d(-hx, hy, 0), along_x, up, -Eigen::Vector3d::UnitY()});
  // A desk against the +y wall with a monitor-sized box on it, and boxes on
  // the floor along the walls; the smallest allowed room (3 x 3) fits them.
  room.addBlock({-hx + 0.8, hy - 0.8, 0.0}, {-hx + 2.4, hy, 0.75});
  room.addBlock({-hx + 1.3, hy - 0.4, 0.75}, {-hx + 1.8, hy - 0.15, 1.05});
  room.addBlock({hx - 1.0, -hy + 0.3, 0.0}, {hx - 0.4, -hy + 0.8, 0.5});
  room.addBlock({-hx + 0.3, -hy + 0.5, 0.0}, {-hx + 0.8, -hy + 1.2, 0.4});
  room.addBlock({hx - 0.7, hy - 1.2, 0.0}, {hx - 0.3, hy - 0.8, 0.35});
  return room;
}

struct SurfacePoint {
  Eigen::Vector3d position;
  Eigen::Vector3d normal;
};

/// Uniform over the visible area of the surfaces: covered points are drawn again.
std::vector<SurfacePoint> placeLandmarks(const Room& room, std::size_t count, RandomSource& random) {
  std::vector<double> cumulative_area;
  double total = 0.0;
  for (const auto& surface : room.surfaces) cumulative_area.push_back(total += surface.area());
  std::vector<SurfacePoint> points;
  points.reserve(count);
  while (points.size() < count) {
    const double pick = random.openUniform(0.0, total);
    std::size_t index = 0;
    while (index + 1 < room.surfaces.size() && cumulative_area[index] < pick) ++index;
    const Rectangle& surface = room.surfaces[index];
    const double s = random.openUnit(), t = random.openUnit();
    const Eigen::Vector3d position = surface.corner + s * surface.edge_a + t * surface.edge_b;
    if (!room.covered(position, surface)) points.push_back({position, surface.normal});
  }
  return points;
}

/// Camera-to-world poses along the arc, each looking at `look_at`.
std::vector<Eigen::Isometry3d> trueTrajectory(const SyntheticSessionOptions& options) {
  const double rx = options.path_radius_fraction * options.room_size.x() / 2;
  const double ry = options.path_radius_fraction * options.room_size.y() / 2;
  const double step = options.num_frames > 1 ? 1.0 / static_cast<double>(options.num_frames - 1) : 0.0;
  std::vector<Eigen::Isometry3d> poses;
  poses.reserve(options.num_frames);
  for (std::size_t k = 0; k < options.num_frames; ++k) {
    const double theta = (options.path_start_deg + options.path_arc_deg * step * static_cast<double>(k)) * kDegree;
    // A slight rise and fall keeps the motion from being planar.
    const Eigen::Vector3d centre(rx * std::cos(theta), ry * std::sin(theta),
                                 options.camera_height + 0.05 * std::sin(2.0 * theta));
    const Eigen::Vector3d view = options.look_at - centre;
    // Negated comparisons: NaN (look_at on the camera) must fail them too.
    if (!(view.norm() > 0.1) || !(view.normalized().cross(Eigen::Vector3d::UnitZ()).norm() > 0.1))
      throw std::invalid_argument(
          "SyntheticSessionOptions::look_at must not be on, or (nearly) straight above or "
          "below, the camera path; it is at frame " +
          std::to_string(k));
    const Eigen::Vector3d forward = view.normalized();
    const Eigen::Vector3d right = forward.cross(Eigen::Vector3d::UnitZ());
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() << right.normalized(), forward.cross(right.normalized()), forward;
    pose.translation() = centre;
    poses.push_back(pose);
  }
  return poses;
}

/// Chains the true frame-to-frame motions, each perturbed by a small random
/// motion: the error of every step stays in all later poses, as in odometry.
std::vector<Eigen::Isometry3d> odometryTrajectory(const SyntheticSessionOptions& options,
                                                  const std::vector<Eigen::Isometry3d>& truth, RandomSource& random) {
  std::vector<Eigen::Isometry3d> poses{truth.front()};
  for (std::size_t k = 1; k < truth.size(); ++k) {
    const Eigen::Vector3d rotation_vector = options.drift_rotation_sigma_deg * kDegree * random.normal3();
    Eigen::Isometry3d error = Eigen::Isometry3d::Identity();
    if (rotation_vector.norm() > 0.0)
      error.linear() = Eigen::AngleAxisd(rotation_vector.norm(), rotation_vector.normalized()).toRotationMatrix();
    error.translation() = options.drift_translation_sigma * random.normal3();
    poses.push_back(poses.back() * (truth[k - 1].inverse() * truth[k]) * error);
  }
  return poses;
}

template <typename T>
void require(bool ok, const char* option, const std::string& rule, const T& value) {
  if (ok) return;
  std::ostringstream message;
  message << "SyntheticSessionOptions::" << option << " " << rule << " (got " << value << ")";
  throw std::invalid_argument(message.str());
}

bool finite(double value) { return std::isfinite(value); }

void validate(const SyntheticSessionOptions& o) {
  require(o.num_frames >= 1 && o.num_frames <= 100000, "num_frames", "must be between 1 and 100000", o.num_frames);
  require(o.num_landmarks >= 1 && o.num_landmarks <= 10000000, "num_landmarks", "must be between 1 and 10000000",
          o.num_landmarks);
  require(o.room_size.allFinite() && o.room_size.x() >= 3.0 && o.room_size.y() >= 3.0 && o.room_size.z() >= 2.0,
          "room_size", "must be at least 3 x 3 x 2 metres (the furniture needs it)", o.room_size.transpose());
  require(o.path_radius_fraction >= 0.0 && o.path_radius_fraction <= 0.9, "path_radius_fraction",
          "must be between 0 and 0.9", o.path_radius_fraction);
  require(o.camera_height >= 1.1 && o.camera_height <= o.room_size.z() - 0.1, "camera_height",
          "must be between 1.1 m (above the furniture) and 0.1 m below the ceiling", o.camera_height);
  require(finite(o.path_start_deg), "path_start_deg", "must be finite", o.path_start_deg);
  require(finite(o.path_arc_deg), "path_arc_deg", "must be finite", o.path_arc_deg);
  require(o.look_at.allFinite(), "look_at", "must be finite", o.look_at.transpose());
  require(o.camera.width >= 1 && o.camera.height >= 1, "camera", "width and height must be >= 1",
          std::to_string(o.camera.width) + "x" + std::to_string(o.camera.height));
  require(finite(o.camera.fx) && finite(o.camera.fy) && o.camera.fx > 0.0 && o.camera.fy > 0.0, "camera",
          "focal lengths fx, fy must be finite and > 0",
          std::to_string(o.camera.fx) + ", " + std::to_string(o.camera.fy));
  require(finite(o.camera.cx) && finite(o.camera.cy), "camera", "principal point cx, cy must be finite",
          std::to_string(o.camera.cx) + ", " + std::to_string(o.camera.cy));
  require(!o.camera.hasDistortion(), "camera", "must have no lens distortion",
          "k1 = " + std::to_string(o.camera.distortion[0]) + ", ...");
  require(o.min_depth > 0.0 && finite(o.min_depth), "min_depth", "must be finite and > 0", o.min_depth);
  require(o.max_depth > o.min_depth && finite(o.max_depth), "max_depth", "must be finite and > min_depth", o.max_depth);
  require(o.max_viewing_angle_deg > 0.0 && o.max_viewing_angle_deg <= 90.0, "max_viewing_angle_deg",
          "must be in (0, 90]", o.max_viewing_angle_deg);
  require(o.detection_probability > 0.0 && o.detection_probability <= 1.0, "detection_probability", "must be in (0, 1]",
          o.detection_probability);
  require(o.pixel_noise_sigma >= 0.0 && finite(o.pixel_noise_sigma), "pixel_noise_sigma", "must be finite and >= 0",
          o.pixel_noise_sigma);
  require(o.depth_noise_coefficient >= 0.0 && finite(o.depth_noise_coefficient), "depth_noise_coefficient",
          "must be finite and >= 0", o.depth_noise_coefficient);
  require(o.drift_rotation_sigma_deg >= 0.0 && finite(o.drift_rotation_sigma_deg), "drift_rotation_sigma_deg",
          "must be finite and >= 0", o.drift_rotation_sigma_deg);
  require(o.drift_translation_sigma >= 0.0 && finite(o.drift_translation_sigma), "drift_translation_sigma",
          "must be finite and >= 0", o.drift_translation_sigma);
}

/// Covariance, in camera coordinates, of the back-projection of pixel (u, v)
/// at `depth`: first-order propagation of independent pixel and depth noise.
Eigen::Matrix3d backProjectionCovariance(const PinholeCamera& camera, double u, double v, double depth,
                                         double pixel_sigma, double depth_sigma) {
  Eigen::Matrix3d jacobian;                                         // d(x, y, z) / d(u, v, depth)
  jacobian << depth / camera.fx, 0.0, (u - camera.cx) / camera.fx,  //
      0.0, depth / camera.fy, (v - camera.cy) / camera.fy,          //
      0.0, 0.0, 1.0;
  const Eigen::Vector3d variances(pixel_sigma * pixel_sigma, pixel_sigma * pixel_sigma, depth_sigma * depth_sigma);
  return jacobian * variances.asDiagonal() * jacobian.transpose();
}

/// What frame k's sensor reports of a landmark: a noisy pixel and depth.
struct Measurement {
  double u, v, depth;
};

/// The observations of the landmarks along the camera path: visibility, the
/// tracker's misses and the sensor's noise, in one fixed draw order.
class Observer {
 public:
  Observer(const SyntheticSessionOptions& options, const Room& room, const std::vector<Eigen::Isometry3d>& truth_poses,
           RandomSource& random)
      : options_(options),
        camera_(options.camera),
        room_(room),
        truth_poses_(truth_poses),
        min_facing_cosine_(std::cos(options.max_viewing_angle_deg * kDegree)),
        random_(random) {
    world_to_camera_.reserve(truth_poses.size());
    for (const Eigen::Isometry3d& pose : truth_poses) world_to_camera_.push_back(pose.inverse());
  }

  /// The measurement of `point` in frame k, if it is seen and detected there.
  std::optional<Measurement> measure(const SurfacePoint& point, std::size_t k) {
    // Cheapest rejections first: range, facing, image, then occlusion.
    const Eigen::Vector3d in_camera = world_to_camera_[k] * point.position;
    if (in_camera.z() < options_.min_depth || in_camera.z() > options_.max_depth) return std::nullopt;
    const Eigen::Vector3d to_camera = truth_poses_[k].translation() - point.position;
    if (point.normal.dot(to_camera) < min_facing_cosine_ * to_camera.norm()) return std::nullopt;
    const Eigen::Vector2d pixel = camera_.project(in_camera);
    if (!camera_.inImage(pixel)) return std::nullopt;
    if (room_.occluded(truth_poses_[k].translation(), point.position)) return std::nullopt;
    if (random_.openUnit() >= options_.detection_probability) return std::nullopt;

    const double u_noise = random_.normal();  // sequenced: draw order fixes the session
    const double v_noise = random_.normal();
    const Eigen::Vector2d noisy_pixel = pixel + options_.pixel_noise_sigma * Eigen::Vector2d(u_noise, v_noise);
    const double depth_sigma = options_.depth_noise_coefficient * in_camera.z() * in_camera.z();
    const double depth = in_camera.z() + depth_sigma * random_.normal();
    // A feature detector cannot report a pixel off the sensor, and a depth
    // camera reports no depth <= 0.
    if (!camera_.inImage(noisy_pixel) || !(depth > 0.0)) return std::nullopt;
    return Measurement{noisy_pixel.x(), noisy_pixel.y(), depth};
  }

 private:
  const SyntheticSessionOptions& options_;
  const PinholeCamera& camera_;
  const Room& room_;
  const std::vector<Eigen::Isometry3d>& truth_poses_;
  std::vector<Eigen::Isometry3d> world_to_camera_;
  const double min_facing_cosine_;
  RandomSource& random_;
};

/// One landmark as the odometry estimates it and as it truly is, summed over
/// its observations until finish() averages them.
class LandmarkAccumulator {
 public:
  LandmarkAccumulator(const SyntheticSessionOptions& options, const std::vector<Eigen::Isometry3d>& truth_poses,
                      const std::vector<Eigen::Isometry3d>& odometry_poses)
      : options_(options), truth_poses_(truth_poses), odometry_poses_(odometry_poses) {}

  void add(std::size_t k, const Measurement& measurement) {
    const PinholeCamera& camera = options_.camera;
    const double u = measurement.u, v = measurement.v, depth = measurement.depth;
    const Observation observation{k, u, v};
    estimated_.observations.push_back(observation);
    truth_.observations.push_back(observation);
    position_sum_ += odometry_poses_[k] * camera.backProject(u, v, depth);
    // The SLAM knows only the measured depth, so it derives its sigma from it.
    const Eigen::Matrix3d in_camera_covariance = backProjectionCovariance(
        camera, u, v, depth, options_.pixel_noise_sigma, options_.depth_noise_coefficient * depth * depth);
    const Eigen::Matrix3d estimated_rotation = odometry_poses_[k].linear();
    const Eigen::Matrix3d truth_rotation = truth_poses_[k].linear();
    estimated_covariance_sum_ += estimated_rotation * in_camera_covariance * estimated_rotation.transpose();
    truth_covariance_sum_ += truth_rotation * in_camera_covariance * truth_rotation.transpose();
  }

  bool observed() const { return !estimated_.observations.empty(); }

  /// Appends the landmark, with the next id, to both maps of `session`.
  void finish(const Eigen::Vector3d& true_position, SyntheticSession& session) {
    const double n = static_cast<double>(estimated_.observations.size());
    estimated_.id = truth_.id = session.estimated.landmarks.size();
    estimated_.position = position_sum_ / n;
    truth_.position = true_position;
    // Covariance of the mean of n independent estimates: their mean covariance / n.
    estimated_.covariance = estimated_covariance_sum_ / (n * n);
    truth_.covariance = truth_covariance_sum_ / (n * n);
    session.estimated.landmarks.push_back(std::move(estimated_));
    session.truth.landmarks.push_back(std::move(truth_));
  }

 private:
  const SyntheticSessionOptions& options_;
  const std::vector<Eigen::Isometry3d>& truth_poses_;
  const std::vector<Eigen::Isometry3d>& odometry_poses_;
  Landmark estimated_, truth_;
  Eigen::Vector3d position_sum_ = Eigen::Vector3d::Zero();
  Eigen::Matrix3d estimated_covariance_sum_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d truth_covariance_sum_ = Eigen::Matrix3d::Zero();
};

}  // namespace

SyntheticSession generateSyntheticSession(const SyntheticSessionOptions& options) {
  validate(options);
  RandomSource layout_random(options.seed, kLayoutStream);
  RandomSource drift_random(options.seed, kDriftStream);
  RandomSource observation_random(options.seed, kObservationStream);

  const Room room = makeRoom(options.room_size);
  const std::vector<SurfacePoint> points = placeLandmarks(room, options.num_landmarks, layout_random);
  SyntheticSession session;
  session.true_camera_poses = trueTrajectory(options);
  const std::vector<Eigen::Isometry3d>& truth_poses = session.true_camera_poses;
  const std::vector<Eigen::Isometry3d> odometry_poses = odometryTrajectory(options, truth_poses, drift_random);
  for (std::size_t k = 0; k < truth_poses.size(); ++k) {
    session.truth.frames.emplace(k, truth_poses[k]);
    session.estimated.frames.emplace(k, odometry_poses[k]);
  }

  Observer observer(options, room, truth_poses, observation_random);
  for (const SurfacePoint& point : points) {
    LandmarkAccumulator landmark(options, truth_poses, odometry_poses);
    for (std::size_t k = 0; k < truth_poses.size(); ++k)
      if (const std::optional<Measurement> measurement = observer.measure(point, k)) landmark.add(k, *measurement);
    if (landmark.observed()) landmark.finish(point.position, session);
  }
  if (session.estimated.landmarks.empty())
    throw std::runtime_error(
        "synthetic session: no landmark is observed from the camera path (check the room, path, "
        "camera and depth range options)");
  return session;
}

}  // namespace weighted_icp::simulation
