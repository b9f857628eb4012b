#include "weighted_icp/simulation/rgbd_sequence.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <random>
#include <stdexcept>
#include <system_error>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <unistd.h>

#include "random_source.h"

namespace weighted_icp::simulation {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegree = kPi / 180.0;

// Independent streams of the one seed, so options do not shift each other's draws.
enum class Stream : std::uint64_t { RoomTextures = 1, ObjectTextures, Path, Noise };
std::uint64_t subSeed(std::uint64_t seed, Stream stream, std::uint64_t index = 0) {
  return simulation::subSeed(seed, static_cast<std::uint64_t>(stream), index);
}

// --- Textures: one image per box face, drawn with cv:: shapes so that corners
// (rectangles, checkers, letters) and blobs (circles) abound at every scale a
// camera 1-4 m away resolves.

// 4 mm: a pixel at 2 m. The moving object passes at 1 m, so finer.
constexpr double kRoomTexelsPerMetre = 250.0, kObjectTexelsPerMetre = 500.0;

cv::Scalar randomColor(RandomSource& random, int low, int high) {
  return cv::Scalar(random.integer(low, high), random.integer(low, high), random.integer(low, high));
}

cv::Mat makeTexture(double width_m, double height_m, double texels_per_metre, std::uint64_t seed) {
  RandomSource random(seed);
  const int cols = std::max(8, static_cast<int>(std::lround(width_m * texels_per_metre)));
  const int rows = std::max(8, static_cast<int>(std::lround(height_m * texels_per_metre)));
  cv::Mat texture(rows, cols, CV_8UC3, randomColor(random, 70, 190));
  const double area = width_m * height_m;
  const auto count = [&](double per_square_metre) { return 1 + static_cast<int>(area * per_square_metre); };
  const auto texels = [&](double metres) { return std::max(1, static_cast<int>(std::lround(metres * texels_per_metre))); };
  const auto stroke = [&] { return texels(random.uniform(0.004, 0.012)); };
  const auto anywhere = [&] { return cv::Point(random.integer(0, cols - 1), random.integer(0, rows - 1)); };

  // Large panels first (posters, doors), so small marks sit on varied grounds.
  for (int n = count(0.8); n > 0; --n) {
    const cv::Point corner = anywhere();
    const cv::Size size(texels(random.uniform(0.2, 0.8)), texels(random.uniform(0.2, 0.8)));
    cv::rectangle(texture, cv::Rect(corner, size), randomColor(random, 40, 220), cv::FILLED);
  }
  for (int n = count(30.0); n > 0; --n) {
    const cv::Point corner = anywhere();
    const cv::Size size(texels(random.uniform(0.02, 0.2)), texels(random.uniform(0.02, 0.2)));
    const int thickness = random.chance(0.6) ? cv::FILLED : stroke();
    cv::rectangle(texture, cv::Rect(corner, size), randomColor(random, 10, 245), thickness, cv::LINE_AA);
  }
  for (int n = count(10.0); n > 0; --n) {  // turned quadrilaterals: corners at all angles
    const cv::Point centre = anywhere();
    const double radius = random.uniform(0.02, 0.12) * texels_per_metre;
    const double angle = random.uniform(0.0, 2.0 * kPi);
    std::array<cv::Point, 4> corners;
    for (int k = 0; k < 4; ++k) {
      const double a = angle + k * kPi / 2.0 + random.uniform(-0.3, 0.3);
      corners[k] = centre + cv::Point(static_cast<int>(radius * std::cos(a)), static_cast<int>(radius * std::sin(a)));
    }
    cv::fillConvexPoly(texture, corners.data(), 4, randomColor(random, 10, 245), cv::LINE_AA);
  }
  for (int n = count(20.0); n > 0; --n) {
    const int thickness = random.chance(0.75) ? cv::FILLED : stroke();
    cv::circle(texture, anywhere(), texels(random.uniform(0.01, 0.08)), randomColor(random, 10, 245), thickness, cv::LINE_AA);
  }
  for (int n = count(10.0); n > 0; --n) {
    const cv::Point start = anywhere();
    const double length = random.uniform(0.05, 0.4) * texels_per_metre;
    const double angle = random.uniform(0.0, 2.0 * kPi);
    const cv::Point end =
        start + cv::Point(static_cast<int>(length * std::cos(angle)), static_cast<int>(length * std::sin(angle)));
    cv::line(texture, start, end, randomColor(random, 10, 245), stroke(), cv::LINE_AA);
  }
  for (int n = count(2.0); n > 0; --n) {  // small checkerboards, as on calibration prints
    const cv::Point origin = anywhere();
    const int square = texels(random.uniform(0.02, 0.04));
    const cv::Scalar dark = randomColor(random, 10, 80), light = randomColor(random, 170, 245);
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c)
        cv::rectangle(texture, cv::Rect(origin + cv::Point(c * square, r * square), cv::Size(square, square)),
                      (r + c) % 2 ? dark : light, cv::FILLED);
  }
  static const std::string kGlyphs = "ABCDEFGHJKLMNPQRSTUVWXYZ0123456789#%&";
  constexpr double kHersheyCapHeight = 22.0;  // texels at font scale 1
  for (int n = count(12.0); n > 0; --n) {  // text-like marks: labels, signs
    std::string word;
    for (int k = random.integer(2, 6); k > 0; --k) word += kGlyphs[random.integer(0, static_cast<int>(kGlyphs.size()) - 1)];
    const double scale = random.uniform(0.03, 0.12) * texels_per_metre / kHersheyCapHeight;
    cv::putText(texture, word, anywhere(), random.chance(0.5) ? cv::FONT_HERSHEY_SIMPLEX : cv::FONT_HERSHEY_DUPLEX,
                scale, randomColor(random, 10, 245), stroke(), cv::LINE_AA);
  }
  return texture;
}

// A face is numbered 2 * axis + (1 on the box's + side, 0 on its - side). Its
// texture's columns run along face_u and its rows down face_v, so walls and box
// sides have their texture upright (v is z).
int faceU(int axis) { return axis == 0 ? 1 : 0; }
int faceV(int axis) { return axis == 2 ? 1 : 2; }

using FaceTextures = std::array<cv::Mat, 6>;

FaceTextures makeBoxTextures(const Eigen::Vector3d& size, double texels_per_metre, std::uint64_t seed) {
  FaceTextures faces;
  for (int face = 0; face < 6; ++face)
    faces[face] = makeTexture(size[faceU(face / 2)], size[faceV(face / 2)], texels_per_metre, mixBits(seed + face));
  return faces;
}

// --- The scene.

const Eigen::Vector3d kRoomSize(6.0, 5.0, 3.0);

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
constexpr double kFramesPerLoop = 800.0;  // about 9 mm and 0.6 deg per frame
constexpr double kTiltDownDeg = 12.0;     // to see the desk and floor below the horizon

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
  SceneBox geometry;
  const FaceTextures* faces = nullptr;
  double texels_per_metre = kRoomTexelsPerMetre;
  bool seen_from_inside = false;  // the room
  bool is_moving_object = false;
};

Eigen::Matrix3d yawRotation(double yaw) { return Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix(); }

}  // namespace

struct SyntheticRgbdSequence::Scene {
  FaceTextures room_faces;
  std::vector<FaceTextures> furniture_faces;
  FaceTextures object_faces;
  double path_start_angle = 0.0;
  std::array<double, 6> path_phases{};
  std::uint64_t noise_seed = 0;
};

io::PinholeCamera syntheticRgbdCamera() {
  io::PinholeCamera camera = io::tumCamera(1);
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
  const io::PinholeCamera& camera = options.camera;
  require(options.frames > 0, "frames must be at least 1");
  // Timestamps are written with microseconds: faster frames would share names.
  require(options.fps > 0.0 && options.fps <= 1000.0, "fps must be in (0, 1000]");
  require(camera.fx > 0.0 && camera.fy > 0.0, "camera fx and fy must be positive");
  require(camera.width > 0 && camera.height > 0, "camera width and height must be positive");
  require(camera.depth_factor > 0.0, "camera depth_factor must be positive");
  require(!camera.hasDistortion(), "camera distortion is not supported (the renderer casts undistorted rays)");
  require(options.depth_noise_coefficient >= 0.0 && std::isfinite(options.depth_noise_coefficient),
          "depth_noise_coefficient must be finite and not negative");
  require(options.min_depth >= 0.0 && options.max_depth > options.min_depth,
          "need 0 <= min_depth < max_depth");
  require(options.max_depth * camera.depth_factor <= 65535.0,
          "max_depth * depth_factor must fit the 16-bit depth image (65535)");
  require(options.max_incidence_deg > 0.0 && options.max_incidence_deg <= 90.0,
          "max_incidence_deg must be in (0, 90]");
}

}  // namespace

SyntheticRgbdSequence::SyntheticRgbdSequence(const SyntheticRgbdOptions& options) : options_(options) {
  validate(options_);
  auto scene = std::make_unique<Scene>();
  const auto& layout = furnitureLayout();
  scene->furniture_faces.resize(layout.size());
  // One job per box, each with its own seed: the result does not depend on threads.
  const int jobs = static_cast<int>(layout.size()) + 2;
  cv::parallel_for_(cv::Range(0, jobs), [&](const cv::Range& range) {
    for (int job = range.start; job < range.end; ++job) {
      if (job < static_cast<int>(layout.size()))
        scene->furniture_faces[job] = makeBoxTextures(layout[job].size, kRoomTexelsPerMetre, subSeed(options_.seed, Stream::RoomTextures, job + 1));
      else if (job == static_cast<int>(layout.size()))
        scene->room_faces = makeBoxTextures(kRoomSize, kRoomTexelsPerMetre, subSeed(options_.seed, Stream::RoomTextures, 0));
      else if (options_.moving_object)
        scene->object_faces = makeBoxTextures(kObjectSize, kObjectTexelsPerMetre, subSeed(options_.seed, Stream::ObjectTextures));
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
Eigen::Vector3d SyntheticRgbdSequence::roomSize() const { return kRoomSize; }
const std::vector<SceneBox>& SyntheticRgbdSequence::furniture() const { return furnitureLayout(); }

double SyntheticRgbdSequence::timestamp(std::size_t i) const { return static_cast<double>(i) / options_.fps; }

namespace {

struct PathPoint {
  Eigen::Vector3d position;
  double heading;  // radians from +x about +z, the direction the camera faces
};

PathPoint pathPoint(double angle_start, const std::array<double, 6>& phase, std::size_t i) {
  const double frame = static_cast<double>(i);
  const auto wave = [&](double amplitude, double period_frames, double phase_offset) {
    return amplitude * std::sin(2.0 * kPi * frame / period_frames + phase_offset);
  };
  const double angle = angle_start + 2.0 * kPi * frame / kFramesPerLoop;
  const Eigen::Vector3d on_ellipse(kPathSemiAxisX * std::cos(angle), kPathSemiAxisY * std::sin(angle), kCameraHeight);
  const Eigen::Vector3d tremor(wave(0.02, 110.0, phase[3]), wave(0.02, 130.0, phase[4]), wave(0.015, 90.0, phase[5]));
  const double heading = std::atan2(on_ellipse.y(), on_ellipse.x()) + wave(12.0 * kDegree, 300.0, phase[0]);
  return {on_ellipse + tremor, heading};
}

}  // namespace

Eigen::Isometry3d SyntheticRgbdSequence::cameraToWorld(std::size_t i) const {
  const auto& phase = scene_->path_phases;
  const PathPoint point = pathPoint(scene_->path_start_angle, phase, i);
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
  const PathPoint middle =
      pathPoint(scene_->path_start_angle, scene_->path_phases, kFirstCrossing + crossing * kCrossingPeriod + kCrossingFrames / 2);
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
/// that can see it (the bounding rectangle of its projected corners).
struct BoxInFrame {
  const TexturedBox* box;
  double cos_yaw, sin_yaw;
  Eigen::Vector3d camera_in_box;
  Eigen::Vector3d half_size;
  cv::Rect pixels;

  Eigen::Vector3d toBox(const Eigen::Vector3d& world) const {
    return {cos_yaw * world.x() + sin_yaw * world.y(), -sin_yaw * world.x() + cos_yaw * world.y(), world.z()};
  }
  Eigen::Vector3d toWorld(const Eigen::Vector3d& local) const {
    return {cos_yaw * local.x() - sin_yaw * local.y(), sin_yaw * local.x() + cos_yaw * local.y(), local.z()};
  }
};

BoxInFrame prepare(const TexturedBox& box, const Eigen::Isometry3d& camera_to_world, const io::PinholeCamera& camera) {
  BoxInFrame prepared{&box, std::cos(box.geometry.yaw), std::sin(box.geometry.yaw), {}, box.geometry.size / 2.0,
                      cv::Rect(0, 0, camera.width, camera.height)};
  prepared.camera_in_box = prepared.toBox(camera_to_world.translation() - box.geometry.center);
  if (box.seen_from_inside) return prepared;
  const Eigen::Isometry3d world_to_camera = camera_to_world.inverse();
  double min_u = std::numeric_limits<double>::infinity(), min_v = min_u, max_u = -min_u, max_v = -min_u;
  int corners_behind = 0;
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d offset((corner & 1 ? 1 : -1) * prepared.half_size.x(),
                                 (corner & 2 ? 1 : -1) * prepared.half_size.y(),
                                 (corner & 4 ? 1 : -1) * prepared.half_size.z());
    const Eigen::Vector3d in_camera = world_to_camera * (box.geometry.center + prepared.toWorld(offset));
    if (in_camera.z() <= 1e-3) {
      ++corners_behind;
      continue;
    }
    const Eigen::Vector2d pixel = camera.project(in_camera);
    min_u = std::min(min_u, pixel.x()), max_u = std::max(max_u, pixel.x());
    min_v = std::min(min_v, pixel.y()), max_v = std::max(max_v, pixel.y());
  }
  // All behind: unseen. Some behind: its outline is unbounded, test every pixel.
  if (corners_behind == 8) prepared.pixels = cv::Rect();
  if (corners_behind > 0) return prepared;
  const cv::Rect bounds(cv::Point(static_cast<int>(std::floor(min_u)) - 1, static_cast<int>(std::floor(min_v)) - 1),
                        cv::Point(static_cast<int>(std::ceil(max_u)) + 2, static_cast<int>(std::ceil(max_v)) + 2));
  prepared.pixels = bounds & prepared.pixels;
  return prepared;
}

struct Hit {
  double t = std::numeric_limits<double>::infinity();  // along a ray whose camera z is 1: the depth
  const BoxInFrame* box = nullptr;
  int axis = 0;
  bool positive_side = false;  // the face on the box's + side of `axis`
};

/// From inside (the room): the face the ray leaves through.
void leaveRoom(const BoxInFrame& room, const Eigen::Vector3d& d, Hit& hit) {
  const Eigen::Vector3d& o = room.camera_in_box;
  for (int axis = 0; axis < 3; ++axis) {
    if (d[axis] == 0.0) continue;
    const bool positive = d[axis] > 0.0;
    const double t = ((positive ? room.half_size[axis] : -room.half_size[axis]) - o[axis]) / d[axis];
    if (t < hit.t) hit = {t, &room, axis, positive};
  }
}

/// From outside: the face the ray enters through, if nearer than `hit` (slab test).
void enterBox(const BoxInFrame& box, const Eigen::Vector3d& world_direction, Hit& hit) {
  const Eigen::Vector3d d = box.toBox(world_direction);
  const Eigen::Vector3d& o = box.camera_in_box;
  double t_near = 0.0, t_far = hit.t;
  int near_axis = -1;
  for (int axis = 0; axis < 3; ++axis) {
    if (d[axis] == 0.0) {
      if (std::abs(o[axis]) > box.half_size[axis]) return;
      continue;
    }
    const double inverse = 1.0 / d[axis];
    double t1 = (-box.half_size[axis] - o[axis]) * inverse, t2 = (box.half_size[axis] - o[axis]) * inverse;
    if (t1 > t2) std::swap(t1, t2);
    if (t1 > t_near) t_near = t1, near_axis = axis;
    t_far = std::min(t_far, t2);
    if (t_near > t_far) return;
  }
  if (near_axis < 0 || t_near >= hit.t) return;  // the camera is inside, or something is nearer
  hit = {t_near, &box, near_axis, d[near_axis] < 0.0};
}

cv::Vec3d sampleBilinear(const cv::Mat& texture, double col, double row) {
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

double shading(const Eigen::Vector3d& point, const Eigen::Vector3d& normal) {
  const Eigen::Vector3d to_lamp = kLampPosition - point;
  const double lamp_distance = to_lamp.norm();
  const double lamp = std::max(0.0, normal.dot(to_lamp) / lamp_distance) / (1.0 + 0.15 * lamp_distance * lamp_distance);
  return kAmbient + kDirectional * std::max(0.0, normal.dot(kLightDirection)) + kLamp * lamp;
}

}  // namespace

SyntheticRgbdFrame SyntheticRgbdSequence::frame(std::size_t i) const {
  if (i >= size())
    throw std::out_of_range("synthetic RGB-D: frame " + std::to_string(i) + " of " + std::to_string(size()));
  const io::PinholeCamera& camera = options_.camera;
  SyntheticRgbdFrame frame;
  frame.timestamp = timestamp(i);
  frame.camera_to_world = cameraToWorld(i);
  frame.color.create(camera.height, camera.width, CV_8UC3);
  frame.depth.create(camera.height, camera.width, CV_16UC1);
  frame.moving_object_mask.create(camera.height, camera.width, CV_8UC1);

  const TexturedBox room{{Eigen::Vector3d(0.0, 0.0, kRoomSize.z() / 2.0), kRoomSize, 0.0},
                         &scene_->room_faces, kRoomTexelsPerMetre, true, false};
  std::vector<TexturedBox> boxes;
  for (std::size_t k = 0; k < furniture().size(); ++k)
    boxes.push_back({furniture()[k], &scene_->furniture_faces[k], kRoomTexelsPerMetre, false, false});
  if (const auto object = movingObject(i))
    boxes.push_back({*object, &scene_->object_faces, kObjectTexelsPerMetre, false, true});
  const BoxInFrame room_in_frame = prepare(room, frame.camera_to_world, camera);
  std::vector<BoxInFrame> boxes_in_frame;
  for (const TexturedBox& box : boxes) {
    BoxInFrame prepared = prepare(box, frame.camera_to_world, camera);
    if (!prepared.pixels.empty()) boxes_in_frame.push_back(prepared);
  }

  const Eigen::Matrix3d rotation = frame.camera_to_world.linear();
  const Eigen::Vector3d camera_position = frame.camera_to_world.translation();
  const Eigen::Vector3d direction_step = rotation.col(0) / camera.fx;  // per pixel column
  const double cos_max_incidence = std::cos(options_.max_incidence_deg * kDegree);
  const std::uint64_t frame_seed = mixBits(scene_->noise_seed ^ mixBits(i));
  const std::vector<float>& normal_deviates = hashedNormalTable();
  const double max_value = std::numeric_limits<std::uint16_t>::max();
  const double disparity_scale = camera.fx * kDisparityBaseline * kDisparitySubpixel;  // subpixel units * metres

  cv::parallel_for_(cv::Range(0, camera.height), [&](const cv::Range& rows) {
    std::vector<const BoxInFrame*> row_boxes;
    for (int v = rows.start; v < rows.end; ++v) {
      row_boxes.clear();
      for (const BoxInFrame& box : boxes_in_frame)
        if (v >= box.pixels.y && v < box.pixels.y + box.pixels.height) row_boxes.push_back(&box);
      const Eigen::Vector3d row_direction = rotation * Eigen::Vector3d(-camera.cx / camera.fx, (v - camera.cy) / camera.fy, 1.0);
      cv::Vec3b* color_row = frame.color.ptr<cv::Vec3b>(v);
      std::uint16_t* depth_row = frame.depth.ptr<std::uint16_t>(v);
      std::uint8_t* mask_row = frame.moving_object_mask.ptr<std::uint8_t>(v);
      for (int u = 0; u < camera.width; ++u) {
        const Eigen::Vector3d direction = row_direction + u * direction_step;
        Hit hit;
        leaveRoom(room_in_frame, direction, hit);
        for (const BoxInFrame* box : row_boxes)
          if (u >= box->pixels.x && u < box->pixels.x + box->pixels.width) enterBox(*box, direction, hit);

        const BoxInFrame& seen = *hit.box;
        const TexturedBox& box = *seen.box;
        // The face's normal towards the camera: outwards for boxes, inwards for the room.
        const double normal_sign = (hit.positive_side != box.seen_from_inside) ? 1.0 : -1.0;
        Eigen::Vector3d local_normal = Eigen::Vector3d::Zero();
        local_normal[hit.axis] = normal_sign;
        const Eigen::Vector3d normal = seen.toWorld(local_normal);
        const Eigen::Vector3d local = seen.camera_in_box + hit.t * seen.toBox(direction);
        // Columns run to the viewer's right (e_v x normal), so text reads the right way round.
        const int u_axis = faceU(hit.axis), v_axis = faceV(hit.axis);
        const double column_sign = hit.axis == 1 ? -normal_sign : normal_sign;
        const cv::Vec3d albedo = sampleBilinear(
            (*box.faces)[2 * hit.axis + (hit.positive_side ? 1 : 0)],
            (column_sign * local[u_axis] + seen.half_size[u_axis]) * box.texels_per_metre - 0.5,
            (seen.half_size[v_axis] - local[v_axis]) * box.texels_per_metre - 0.5);
        const double light = shading(camera_position + hit.t * direction, normal);

        const std::uint64_t pixel_hash = mixBits(frame_seed ^ static_cast<std::uint64_t>(v * camera.width + u));
        const double image_noise = normal_deviates[pixel_hash & 0xffff];
        const double depth_noise = normal_deviates[(pixel_hash >> 16) & 0xffff];
        for (int k = 0; k < 3; ++k) {
          const double radiance = std::min(1.0, albedo[k] * light * (1.0 / 255.0));
          static_assert(kDimGamma == 1.5, "the dim image's gamma is computed as r * sqrt(r)");
          const double value = options_.dim_lighting
                                   ? kDimBlackLevel + 255.0 * kDimGain * radiance * std::sqrt(radiance) +
                                         kDimNoiseSigma * image_noise
                                   : 255.0 * radiance + kNoiseSigma * image_noise;
          color_row[u][k] = cv::saturate_cast<std::uint8_t>(value);
        }

        double depth = hit.t;
        const double cos_incidence = std::abs(normal.dot(direction)) / direction.norm();
        const bool measurable =
            depth >= options_.min_depth && depth <= options_.max_depth && cos_incidence >= cos_max_incidence;
        if (measurable && options_.depth_noise) {
          depth += options_.depth_noise_coefficient * depth * depth * depth_noise;
          // Values are positive: truncating x + 0.5 rounds, without a libm call.
          depth = disparity_scale / std::max(1.0, std::trunc(disparity_scale / depth + 0.5));
        }
        const double stored = depth * camera.depth_factor + 0.5;
        depth_row[u] = measurable && stored < max_value + 1.0 ? static_cast<std::uint16_t>(stored) : 0;
        mask_row[u] = box.is_moving_object ? 255 : 0;
      }
    }
  });
  return frame;
}

// --- The TUM RGB-D layout.

namespace {

std::string timestampText(double timestamp) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.6f", timestamp);
  return text;
}

void writeImage(const std::filesystem::path& path, const cv::Mat& image) {
  if (!cv::imwrite(path.string(), image)) throw std::runtime_error("cannot write " + path.string());
}

}  // namespace

void writeTumSequence(const SyntheticRgbdSequence& sequence, const std::string& dir, bool overwrite,
                      const std::function<void(std::size_t)>& frame_written) {
  namespace fs = std::filesystem;
  fs::path target = fs::path(dir).lexically_normal();
  if (!target.has_filename()) target = target.parent_path();  // "out/" names "out"
  if (target.empty()) throw std::runtime_error("writeTumSequence: no folder given");
  std::error_code error;
  if (fs::exists(target, error)) {
    if (!fs::is_directory(target)) throw std::runtime_error(target.string() + " exists and is not a folder");
    if (!fs::is_empty(target) && !overwrite)
      throw std::runtime_error(target.string() + " exists and is not empty; not overwriting it");
  }
  const fs::path parent = target.has_parent_path() ? target.parent_path() : fs::path(".");
  fs::create_directories(parent, error);
  if (error) throw std::runtime_error("cannot create " + parent.string() + ": " + error.message());

  // Beside the target, so the final rename stays on one file system.
  fs::path temporary;
  for (int attempt = 0;; ++attempt) {
    temporary = parent / (target.filename().string() + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(attempt));
    if (fs::create_directory(temporary, error)) break;
    if (error) throw std::runtime_error("cannot write in " + parent.string() + ": " + error.message());
  }
  try {
    fs::create_directory(temporary / "rgb");
    fs::create_directory(temporary / "depth");
    std::ofstream rgb_list(temporary / "rgb.txt"), depth_list(temporary / "depth.txt"),
        groundtruth(temporary / "groundtruth.txt");
    rgb_list << "# color images\n# synthetic RGB-D sequence, seed " << sequence.options().seed
             << "\n# timestamp filename\n";
    depth_list << "# depth maps\n# synthetic RGB-D sequence, seed " << sequence.options().seed
               << "\n# timestamp filename\n";
    groundtruth << "# ground truth trajectory (camera to world, exact)\n# synthetic RGB-D sequence, seed "
                << sequence.options().seed << "\n# timestamp tx ty tz qx qy qz qw\n"
                << std::setprecision(std::numeric_limits<double>::max_digits10);
    for (std::size_t i = 0; i < sequence.size(); ++i) {
      const SyntheticRgbdFrame frame = sequence.frame(i);
      const std::string stamp = timestampText(frame.timestamp);
      writeImage(temporary / "rgb" / (stamp + ".png"), frame.color);
      writeImage(temporary / "depth" / (stamp + ".png"), frame.depth);
      rgb_list << stamp << " rgb/" << stamp << ".png\n";
      depth_list << stamp << " depth/" << stamp << ".png\n";
      Eigen::Quaterniond rotation(frame.camera_to_world.linear());
      if (rotation.w() < 0.0) rotation.coeffs() = -rotation.coeffs();  // one of the two equal quaternions
      const Eigen::Vector3d& t = frame.camera_to_world.translation();
      groundtruth << stamp << ' ' << t.x() << ' ' << t.y() << ' ' << t.z() << ' ' << rotation.x() << ' '
                  << rotation.y() << ' ' << rotation.z() << ' ' << rotation.w() << '\n';
      if (frame_written) frame_written(i);
    }
    for (std::ofstream* list : {&rgb_list, &depth_list, &groundtruth}) {
      list->close();
      if (!*list) throw std::runtime_error("cannot write the lists in " + temporary.string());
    }
    if (fs::exists(target) && !fs::is_empty(target)) {
      // Replace: move the old folder aside, the new one in, then delete the old.
      const fs::path old = temporary.string() + ".old";
      fs::rename(target, old);
      fs::rename(temporary, target, error);
      if (error) {
        fs::rename(old, target);
        throw fs::filesystem_error("rename", temporary, target, error);
      }
      fs::remove_all(old, error);
    } else {
      fs::rename(temporary, target);  // replaces an empty folder
    }
  } catch (const fs::filesystem_error& e) {
    fs::remove_all(temporary, error);
    throw std::runtime_error("cannot write " + target.string() + ": " + e.code().message());
  } catch (...) {
    fs::remove_all(temporary, error);
    throw;
  }
}

}  // namespace weighted_icp::simulation
