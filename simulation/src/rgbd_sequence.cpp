// The synthetic RGB-D sequence (see rgbd_sequence.h): the room and its
// furniture, the camera path, the moving object, and the renderer that ray
// casts them into colour and depth images as a Kinect-like sensor would.

#include "weighted_icp/simulation/rgbd_sequence.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "random_source.h"
#include "raycasting.h"
#include "textures.h"
#include "weighted_icp/core/parallel_for.h"

namespace weighted_icp::simulation {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegree = kPi / 180.0;

// Independent streams of the one seed, so options do not shift each other's draws.
enum class Stream : std::uint64_t { RoomTextures = 1, ObjectTextures, Path, Noise };
std::uint64_t subSeed(std::uint64_t seed, Stream stream, std::uint64_t index = 0) {
  return simulation::subSeed(seed, static_cast<std::uint64_t>(stream), index);
}

// --- The scene.

// Texture resolution: 4 mm, a pixel at 2 m. The moving object passes at 1 m, so finer.
constexpr double kRoomTexelsPerMetre = 250.0, kObjectTexelsPerMetre = 500.0;

const Eigen::Vector3d kRoomSize(6.0, 5.0, 3.0);  // at room_scale 1

// The repeated texture's tile (perceptual aliasing): a square metre, about what the camera sees of a wall
// two metres away in a third of the image, so every view holds a few copies of it.
constexpr double kRepeatedTileMetres = 1.0;

// A desk with a monitor and a box on it against the +y wall, a cabinet, a low
// shelf and boxes along the others: all outside the camera's path (below).
const std::vector<SceneBox>& furnitureLayout() {
  static const std::vector<SceneBox> layout = {
      {{-0.8, 2.1, 0.375}, {1.6, 0.8, 0.75}, 0.0},    // desk
      {{-0.9, 2.35, 0.925}, {0.6, 0.06, 0.35}, 0.0},  // monitor
      {{-0.15, 2.0, 0.86}, {0.3, 0.25, 0.22}, 0.35},  // box on the desk
      {{2.65, 1.4, 0.9}, {0.6, 0.5, 1.8}, 0.0},       // cabinet
      {{1.7, -2.05, 0.25}, {0.6, 0.5, 0.5}, 0.25},    // box on the floor
      {{1.7, -2.05, 0.65}, {0.4, 0.35, 0.3}, -0.2},   // and one on top of it
      {{-2.7, 0.6, 0.45}, {0.5, 1.4, 0.9}, 0.0},      // low shelf
      {{-2.0, -1.9, 0.3}, {0.7, 0.6, 0.6}, 0.5},      // crate
      {{0.6, -2.2, 0.2}, {0.3, 0.3, 0.4}, 0.0},       // bin
  };
  return layout;
}

// The camera path: an ellipse around the room's centre at eye height, looking
// outwards at the walls and furniture, with slow sway and hand tremor. Rates
// are per frame (not per second) since they set how far a tracker must follow.
constexpr double kPathSemiAxisX = 1.1, kPathSemiAxisY = 0.85, kCameraHeight = 1.4;
constexpr double kTiltDownDeg = 12.0;  // to see the desk and floor below the horizon

// The moving object: a box carried past, kObjectDistance in front of the
// camera, crossing the view in kCrossingFrames frames every kCrossingPeriod
// frames from frame kFirstCrossing on.
const Eigen::Vector3d kObjectSize(0.35, 0.5, 0.4);
constexpr double kObjectDistance = 1.2, kObjectHalfTravel = 1.2, kObjectBelowCamera = 0.1;
constexpr std::size_t kFirstCrossing = 25, kCrossingPeriod = 100, kCrossingFrames = 60;

// Lighting: ambient, a directional light (so faces of different orientation
// differ) and a lamp under the ceiling (so shading varies along a surface).
const Eigen::Vector3d kLightDirection = Eigen::Vector3d(0.45, -0.35, 0.82).normalized();
const Eigen::Vector3d kLampPosition(0.4, -0.3, 2.8);
constexpr double kAmbient = 0.45, kDirectional = 0.3, kLamp = 1.2;

// Colour camera: sensor noise sigma (grey levels); dim light scales the
// radiance by a gain, darkens mid-tones by a gamma and adds more noise.
constexpr double kNoiseSigma = 1.0;
constexpr double kDimGain = 0.25, kDimGamma = 1.5, kDimBlackLevel = 4.0, kDimNoiseSigma = 3.0;

// Kinect-like depth: the disparity over this baseline is quantised to this
// fraction of a pixel.
constexpr double kDisparityBaseline = 0.075, kDisparitySubpixel = 8.0;

struct TexturedBox {
  RayBox shape;
  const FaceTextures* faces = nullptr;
  double texels_per_metre = kRoomTexelsPerMetre;
  bool seen_from_inside = false;  // the room
  bool is_moving_object = false;
};

TexturedBox texturedBox(const SceneBox& box, const FaceTextures* faces, double texels_per_metre,
                        bool is_moving_object) {
  return {RayBox::centred(box.center, box.size, box.yaw), faces, texels_per_metre, false, is_moving_object};
}

Eigen::Matrix3d yawRotation(double yaw) { return Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix(); }

}  // namespace

struct SyntheticRgbdSequence::Scene {
  Eigen::Vector3d room_size = kRoomSize;
  std::vector<SceneBox> furniture;  // furnitureLayout() with room_scale applied to the floor positions
  FaceTextures room_faces;
  std::vector<FaceTextures> furniture_faces;
  FaceTextures object_faces;
  double path_start_angle = 0.0;
  std::array<double, 6> path_phases{};
  std::uint64_t noise_seed = 0;
};

PinholeCamera syntheticRgbdCamera() {
  PinholeCamera camera = tumCamera(1);
  camera.distortion = {};
  camera.width = 640;
  camera.height = 480;
  camera.depth_factor = 5000.0;
  return camera;
}

namespace {

void validate(const SyntheticRgbdOptions& options) {
  const auto require = [](bool ok, const std::string& message) {
    if (!ok) throw std::invalid_argument("synthetic RGB-D: " + message);
  };
  const PinholeCamera& camera = options.camera;
  require(options.frames > 0, "frames must be at least 1");
  require(std::isfinite(options.frames_per_loop) && options.frames_per_loop >= 10.0,
          "frames_per_loop must be finite and at least 10");
  // Timestamps are written with microseconds: faster frames would share names.
  require(options.fps > 0.0 && options.fps <= 1000.0, "fps must be in (0, 1000]");
  require(camera.fx > 0.0 && camera.fy > 0.0, "camera fx and fy must be positive");
  require(camera.width > 0 && camera.height > 0, "camera width and height must be positive");
  require(camera.depth_factor > 0.0, "camera depth_factor must be positive");
  require(!camera.hasDistortion(), "camera distortion is not supported (the renderer casts undistorted rays)");
  require(options.depth_noise_coefficient >= 0.0 && std::isfinite(options.depth_noise_coefficient),
          "depth_noise_coefficient must be finite and not negative");
  require(std::abs(options.depth_distortion) <= 0.1, "depth_distortion must be in [-0.1, 0.1]");
  require(options.min_depth >= 0.0 && options.max_depth > options.min_depth, "need 0 <= min_depth < max_depth");
  require(options.max_depth * camera.depth_factor <= 65535.0,
          "max_depth * depth_factor must fit the 16-bit depth image (65535)");
  require(options.max_incidence_deg > 0.0 && options.max_incidence_deg <= 90.0, "max_incidence_deg must be in (0, 90]");
  require(options.room_scale >= 1.0 && options.room_scale <= 4.0, "room_scale must be in [1, 4]");
  // A focal length off by a fifth or a principal point a sixth of the image away is not a calibration error
  // but a different camera; the bounds also keep the tracker's camera valid.
  require(std::abs(options.focal_length_error) <= 0.2, "focal_length_error must be in [-0.2, 0.2]");
  require(std::abs(options.principal_point_error_x_px) <= camera.width / 6.0 &&
              std::abs(options.principal_point_error_y_px) <= camera.height / 6.0,
          "principal_point_error_x_px, _y_px must be within a sixth of the image's width, height");
}

}  // namespace

SyntheticRgbdSequence::SyntheticRgbdSequence(const SyntheticRgbdOptions& options) : options_(options) {
  validate(options_);
  auto scene = std::make_unique<Scene>();
  scene->room_size =
      Eigen::Vector3d(kRoomSize.x() * options_.room_scale, kRoomSize.y() * options_.room_scale, kRoomSize.z());
  scene->furniture = furnitureLayout();
  for (SceneBox& box : scene->furniture) box.center.head<2>() *= options_.room_scale;
  const auto& layout = scene->furniture;
  scene->furniture_faces.resize(layout.size());
  // One job per box, each with its own seed: the result does not depend on threads.
  const int jobs = static_cast<int>(layout.size()) + 2;
  const std::uint64_t seed = options_.seed;
  // One square metre of texture, repeated on every face, when aliasing is asked for.
  const cv::Mat tile = options_.repeated_texture
                           ? makeTexture(kRepeatedTileMetres, kRepeatedTileMetres, kRoomTexelsPerMetre,
                                         subSeed(seed, Stream::RoomTextures, 0))
                           : cv::Mat();
  const auto boxTextures = [&](const Eigen::Vector3d& size, std::uint64_t box_seed) {
    return options_.repeated_texture ? makeRepeatedBoxTextures(size, kRoomTexelsPerMetre, tile)
                                     : makeBoxTextures(size, kRoomTexelsPerMetre, box_seed);
  };
  parallelFor(cv::Range(0, jobs), [&](const cv::Range& range) {
    for (int job = range.start; job < range.end; ++job) {
      if (job < static_cast<int>(layout.size()))
        scene->furniture_faces[job] = boxTextures(layout[job].size, subSeed(seed, Stream::RoomTextures, job + 1));
      else if (job == static_cast<int>(layout.size()))
        scene->room_faces = boxTextures(scene->room_size, subSeed(seed, Stream::RoomTextures, 0));
      else if (options_.moving_object)
        scene->object_faces =
            makeBoxTextures(kObjectSize, kObjectTexelsPerMetre, subSeed(seed, Stream::ObjectTextures));
    }
  });
  RandomSource path_random(subSeed(options_.seed, Stream::Path));
  scene->path_start_angle = path_random.uniform(0.0, 2.0 * kPi);
  for (double& phase : scene->path_phases) phase = path_random.uniform(0.0, 2.0 * kPi);
  scene->noise_seed = subSeed(options_.seed, Stream::Noise);
  scene_ = std::move(scene);
}

SyntheticRgbdSequence::~SyntheticRgbdSequence() = default;
SyntheticRgbdSequence::SyntheticRgbdSequence(SyntheticRgbdSequence&&) noexcept = default;
SyntheticRgbdSequence& SyntheticRgbdSequence::operator=(SyntheticRgbdSequence&&) noexcept = default;

std::size_t SyntheticRgbdSequence::size() const { return options_.frames; }
const SyntheticRgbdOptions& SyntheticRgbdSequence::options() const { return options_; }

PinholeCamera SyntheticRgbdSequence::trackerCamera() const {
  PinholeCamera camera = options_.camera;
  camera.fx *= 1.0 + options_.focal_length_error;
  camera.fy *= 1.0 + options_.focal_length_error;
  camera.cx += options_.principal_point_error_x_px;
  camera.cy += options_.principal_point_error_y_px;
  return camera;
}
Eigen::Vector3d SyntheticRgbdSequence::roomSize() const { return scene_->room_size; }
const std::vector<SceneBox>& SyntheticRgbdSequence::furniture() const { return scene_->furniture; }

double SyntheticRgbdSequence::timestamp(std::size_t i) const { return static_cast<double>(i) / options_.fps; }

namespace {

struct PathPoint {
  Eigen::Vector3d position;
  double heading;  // radians from +x about +z, the direction the camera faces
};

PathPoint pathPoint(double angle_start, const std::array<double, 6>& phase, double frames_per_loop, double room_scale,
                    std::size_t i) {
  const double frame = static_cast<double>(i);
  const auto wave = [&](double amplitude, double period_frames, double phase_offset) {
    return amplitude * std::sin(2.0 * kPi * frame / period_frames + phase_offset);
  };
  const double angle = angle_start + 2.0 * kPi * frame / frames_per_loop;
  const Eigen::Vector3d on_ellipse(room_scale * kPathSemiAxisX * std::cos(angle),
                                   room_scale * kPathSemiAxisY * std::sin(angle), kCameraHeight);
  const Eigen::Vector3d tremor(wave(0.02, 110.0, phase[3]), wave(0.02, 130.0, phase[4]), wave(0.015, 90.0, phase[5]));
  const double heading = std::atan2(on_ellipse.y(), on_ellipse.x()) + wave(12.0 * kDegree, 300.0, phase[0]);
  return {on_ellipse + tremor, heading};
}

}  // namespace

Eigen::Isometry3d SyntheticRgbdSequence::cameraToWorld(std::size_t i) const {
  const auto& phase = scene_->path_phases;
  const PathPoint point = pathPoint(scene_->path_start_angle, phase, options_.frames_per_loop, options_.room_scale, i);
  const double frame = static_cast<double>(i);
  const double tilt_down = (kTiltDownDeg + 4.0 * std::sin(2.0 * kPi * frame / 210.0 + phase[1])) * kDegree;
  const double roll = 2.0 * kDegree * std::sin(2.0 * kPi * frame / 170.0 + phase[2]);
  // Body axes: x forward, y left, z up; a camera's are x right, y down, z forward.
  Eigen::Matrix3d body_to_camera_axes;
  body_to_camera_axes << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  const Eigen::Matrix3d body_to_world = yawRotation(point.heading) *
                                        Eigen::AngleAxisd(tilt_down, Eigen::Vector3d::UnitY()).toRotationMatrix() *
                                        Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()).toRotationMatrix();
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = body_to_world * body_to_camera_axes;
  pose.translation() = point.position;
  return pose;
}

std::optional<SceneBox> SyntheticRgbdSequence::movingObject(std::size_t i) const {
  if (!options_.moving_object || i < kFirstCrossing) return std::nullopt;
  const std::size_t crossing = (i - kFirstCrossing) / kCrossingPeriod;
  const std::size_t step = (i - kFirstCrossing) % kCrossingPeriod;
  if (step >= kCrossingFrames) return std::nullopt;
  // A straight line in the world, across the view of the crossing's middle frame.
  const std::size_t middle_frame = kFirstCrossing + crossing * kCrossingPeriod + kCrossingFrames / 2;
  const PathPoint middle = pathPoint(scene_->path_start_angle, scene_->path_phases, options_.frames_per_loop,
                                     options_.room_scale, middle_frame);
  const Eigen::Vector3d forward(std::cos(middle.heading), std::sin(middle.heading), 0.0);
  const Eigen::Vector3d left(-forward.y(), forward.x(), 0.0);
  const double progress = (static_cast<double>(step) + 0.5) / kCrossingFrames;  // (0, 1)
  const double direction = crossing % 2 == 0 ? -1.0 : 1.0;                      // alternately right and left
  SceneBox object;
  object.size = kObjectSize;
  object.center = middle.position + kObjectDistance * forward +
                  direction * kObjectHalfTravel * (2.0 * progress - 1.0) * left -
                  kObjectBelowCamera * Eigen::Vector3d::UnitZ();
  object.yaw = middle.heading + 0.5 * (progress - 0.5);  // turning slowly as it is carried
  return object;
}

// --- Rendering: one ray per pixel through its centre, nearest hit among the
// room (seen from inside) and the boxes. Rows are independent, and noise is a
// hash of (seed, frame, pixel): the result does not depend on threads.

namespace {

/// A box as seen in one frame: the camera in the box's frame, and the pixels
/// that can see it.
struct BoxInFrame {
  const TexturedBox* box;
  Eigen::Vector3d camera_in_box;
  cv::Rect pixels;
};

BoxInFrame prepare(const TexturedBox& box, const Eigen::Isometry3d& camera_to_world, const PinholeCamera& camera) {
  return {&box, box.shape.pointInBox(camera_to_world.translation()),
          box.seen_from_inside ? cv::Rect(0, 0, camera.width, camera.height)
                               : pixelBounds(box.shape, camera_to_world, camera)};
}

struct Hit {
  FaceHit face;  // t along a ray whose camera z is 1: the depth
  const BoxInFrame* box = nullptr;
};

double shading(const Eigen::Vector3d& point, const Eigen::Vector3d& normal) {
  const Eigen::Vector3d to_lamp = kLampPosition - point;
  const double lamp_distance = to_lamp.norm();
  const double lamp = std::max(0.0, normal.dot(to_lamp) / lamp_distance) / (1.0 + 0.15 * lamp_distance * lamp_distance);
  return kAmbient + kDirectional * std::max(0.0, normal.dot(kLightDirection)) + kLamp * lamp;
}

/// Renders the pixels of one frame: what is fixed for the frame, and the steps
/// of one pixel (cast, shade, measure depth).
class FrameRenderer {
 public:
  FrameRenderer(const SyntheticRgbdOptions& options, const std::vector<BoxInFrame>& boxes, const BoxInFrame& room,
                const Eigen::Isometry3d& camera_to_world, std::uint64_t frame_seed)
      : options_(options),
        camera_(options.camera),
        boxes_(boxes),
        room_(room),
        rotation_(camera_to_world.linear()),
        camera_position_(camera_to_world.translation()),
        direction_step_(rotation_.col(0) / camera_.fx),  // per pixel column
        cos_max_incidence_(std::cos(options.max_incidence_deg * kDegree)),
        frame_seed_(frame_seed),
        normal_deviates_(hashedNormalTable()),
        disparity_scale_(camera_.fx * kDisparityBaseline * kDisparitySubpixel) {  // subpixel units * metres
    column_radius_squared_.resize(static_cast<std::size_t>(camera_.width));
    for (int u = 0; u < camera_.width; ++u)
      column_radius_squared_[static_cast<std::size_t>(u)] = std::pow((u - camera_.cx) / camera_.fx, 2);
  }

  /// Row v of the colour image, the raw 16-bit depth (as the sensor stores
  /// it) and the moving-object mask.
  void renderRow(int v, SyntheticRgbdFrame& frame, cv::Mat& raw_depth,
                 std::vector<const BoxInFrame*>& row_boxes) const {
    row_boxes.clear();
    for (const BoxInFrame& box : boxes_)
      if (v >= box.pixels.y && v < box.pixels.y + box.pixels.height) row_boxes.push_back(&box);
    const Eigen::Vector3d row_direction =
        rotation_ * Eigen::Vector3d(-camera_.cx / camera_.fx, (v - camera_.cy) / camera_.fy, 1.0);
    const double row_radius_squared = std::pow((v - camera_.cy) / camera_.fy, 2);
    cv::Vec3b* color_row = frame.rgbd.color.ptr<cv::Vec3b>(v);
    std::uint16_t* depth_row = raw_depth.ptr<std::uint16_t>(v);
    std::uint8_t* mask_row = frame.moving_object_mask.ptr<std::uint8_t>(v);
    for (int u = 0; u < camera_.width; ++u) {
      const Eigen::Vector3d direction = row_direction + u * direction_step_;
      const Hit hit = cast(u, direction, row_boxes);
      const Eigen::Vector3d normal = hit.box->box->shape.toWorld(localNormal(hit));
      const std::uint64_t pixel_hash = mixBits(frame_seed_ ^ static_cast<std::uint64_t>(v * camera_.width + u));
      color_row[u] = color(hit, direction, normal, normal_deviates_[pixel_hash & 0xffff]);
      depth_row[u] = depth(
          hit.face.t, direction, normal, normal_deviates_[(pixel_hash >> 16) & 0xffff],
          1.0 + options_.depth_distortion * (row_radius_squared + column_radius_squared_[static_cast<std::size_t>(u)]));
      mask_row[u] = hit.box->box->is_moving_object ? 255 : 0;
    }
  }

 private:
  /// The nearest face along the ray: the room's wall it leaves through, unless
  /// a box whose pixels include u is entered first.
  Hit cast(int u, const Eigen::Vector3d& direction, const std::vector<const BoxInFrame*>& row_boxes) const {
    Hit hit;
    room_.box->shape.leave(room_.camera_in_box, room_.box->shape.toBox(direction), hit.face);
    hit.box = &room_;
    for (const BoxInFrame* box : row_boxes)
      if (u >= box->pixels.x && u < box->pixels.x + box->pixels.width &&
          box->box->shape.enter(box->camera_in_box, box->box->shape.toBox(direction), hit.face))
        hit.box = box;
    return hit;
  }

  /// The face's normal towards the camera, in the box's frame: outwards for
  /// boxes, inwards for the room.
  static Eigen::Vector3d localNormal(const Hit& hit) {
    Eigen::Vector3d local_normal = Eigen::Vector3d::Zero();
    local_normal[hit.face.axis] = normalSign(hit);
    return local_normal;
  }
  static double normalSign(const Hit& hit) {
    return (hit.face.positive_side != hit.box->box->seen_from_inside) ? 1.0 : -1.0;
  }

  /// Texture times lighting, then the sensor's response and noise.
  cv::Vec3b color(const Hit& hit, const Eigen::Vector3d& direction, const Eigen::Vector3d& normal,
                  double image_noise) const {
    const BoxInFrame& seen = *hit.box;
    const TexturedBox& box = *seen.box;
    const Eigen::Vector3d local = seen.camera_in_box + hit.face.t * box.shape.toBox(direction);
    // Columns run to the viewer's right (e_v x normal), so text reads the right way round.
    const int axis = hit.face.axis, u_axis = faceU(axis), v_axis = faceV(axis);
    const double column_sign = axis == 1 ? -normalSign(hit) : normalSign(hit);
    const cv::Vec3d albedo =
        sampleBilinear((*box.faces)[2 * axis + (hit.face.positive_side ? 1 : 0)],
                       (column_sign * local[u_axis] + box.shape.upper()[u_axis]) * box.texels_per_metre - 0.5,
                       (box.shape.upper()[v_axis] - local[v_axis]) * box.texels_per_metre - 0.5);
    const double light = shading(camera_position_ + hit.face.t * direction, normal);
    cv::Vec3b pixel;
    for (int k = 0; k < 3; ++k) {
      const double radiance = std::min(1.0, albedo[k] * light * (1.0 / 255.0));
      static_assert(kDimGamma == 1.5, "the dim image's gamma is computed as r * sqrt(r)");
      const double value = options_.dim_lighting ? kDimBlackLevel + 255.0 * kDimGain * radiance * std::sqrt(radiance) +
                                                       kDimNoiseSigma * image_noise
                                                 : 255.0 * radiance + kNoiseSigma * image_noise;
      pixel[k] = cv::saturate_cast<std::uint8_t>(value);
    }
    return pixel;
  }

  /// The stored depth of a hit at `t` (the depth, as the ray's camera z is 1):
  /// 0 out of the sensor's range or incidence, else distorted by `distortion` (a factor), noisy and quantised
  /// as a Kinect's if asked.
  std::uint16_t depth(double t, const Eigen::Vector3d& direction, const Eigen::Vector3d& normal, double depth_noise,
                      double distortion) const {
    double depth = t;
    const double cos_incidence = std::abs(normal.dot(direction)) / direction.norm();
    const bool measurable =
        depth >= options_.min_depth && depth <= options_.max_depth && cos_incidence >= cos_max_incidence_;
    if (measurable) depth *= distortion;
    if (measurable && options_.depth_noise) {
      depth += options_.depth_noise_coefficient * depth * depth * depth_noise;
      // Values are positive: truncating x + 0.5 rounds, without a libm call.
      depth = disparity_scale_ / std::max(1.0, std::trunc(disparity_scale_ / depth + 0.5));
    }
    const double stored = depth * camera_.depth_factor + 0.5;
    constexpr double kMaxValue = std::numeric_limits<std::uint16_t>::max();
    return measurable && stored < kMaxValue + 1.0 ? static_cast<std::uint16_t>(stored) : 0;
  }

  const SyntheticRgbdOptions& options_;
  const PinholeCamera& camera_;
  const std::vector<BoxInFrame>& boxes_;
  const BoxInFrame& room_;
  const Eigen::Matrix3d rotation_;
  const Eigen::Vector3d camera_position_, direction_step_;
  const double cos_max_incidence_;
  const std::uint64_t frame_seed_;
  const std::vector<float>& normal_deviates_;
  const double disparity_scale_;
  std::vector<double> column_radius_squared_;  // ((u - cx) / fx)^2 per column, for the depth distortion
};

}  // namespace

SyntheticRgbdFrame SyntheticRgbdSequence::frame(std::size_t i) const {
  if (i >= size())
    throw std::out_of_range("synthetic RGB-D: frame " + std::to_string(i) + " of " + std::to_string(size()));
  const PinholeCamera& camera = options_.camera;
  SyntheticRgbdFrame frame;
  frame.rgbd.timestamp = timestamp(i);
  frame.camera_to_world = cameraToWorld(i);
  frame.rgbd.color.create(camera.height, camera.width, CV_8UC3);
  cv::Mat raw_depth(camera.height, camera.width, CV_16UC1);
  frame.moving_object_mask.create(camera.height, camera.width, CV_8UC1);

  const Eigen::Vector3d& room_size = scene_->room_size;
  const TexturedBox room{RayBox::centred(Eigen::Vector3d(0.0, 0.0, room_size.z() / 2.0), room_size, 0.0),
                         &scene_->room_faces, kRoomTexelsPerMetre, true, false};
  std::vector<TexturedBox> boxes;
  for (std::size_t k = 0; k < furniture().size(); ++k)
    boxes.push_back(texturedBox(furniture()[k], &scene_->furniture_faces[k], kRoomTexelsPerMetre, false));
  if (const auto object = movingObject(i))
    boxes.push_back(texturedBox(*object, &scene_->object_faces, kObjectTexelsPerMetre, true));
  const BoxInFrame room_in_frame = prepare(room, frame.camera_to_world, camera);
  std::vector<BoxInFrame> boxes_in_frame;
  for (const TexturedBox& box : boxes) {
    BoxInFrame prepared = prepare(box, frame.camera_to_world, camera);
    if (!prepared.pixels.empty()) boxes_in_frame.push_back(prepared);
  }

  const FrameRenderer renderer(options_, boxes_in_frame, room_in_frame, frame.camera_to_world,
                               mixBits(scene_->noise_seed ^ mixBits(i)));
  parallelFor(cv::Range(0, camera.height), [&](const cv::Range& rows) {
    std::vector<const BoxInFrame*> row_boxes;
    for (int v = rows.start; v < rows.end; ++v) renderer.renderRow(v, frame, raw_depth, row_boxes);
  });
  frame.rgbd.depth = depthFromRaw(raw_depth, camera.depth_factor);
  return frame;
}

}  // namespace weighted_icp::simulation
