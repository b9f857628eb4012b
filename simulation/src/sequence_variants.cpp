// Sequence variants written in the TUM layout (see sequence_variants.h): the
// degradations of image_degradations.h applied frame by frame into an
// io::AtomicFolder, with the camera, lists and ground truth that go with them.

#include "weighted_icp/simulation/sequence_variants.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "weighted_icp/io/atomic_folder.h"
#include "weighted_icp/io/camera.h"
#include "weighted_icp/simulation/image_degradations.h"

#include "random_source.h"

namespace weighted_icp::simulation {

namespace {

namespace fs = std::filesystem;

const std::vector<std::pair<VariantKind, const char*>>& kindNames() {
  static const std::vector<std::pair<VariantKind, const char*>> names = {
      {VariantKind::Jpeg, "jpeg"},
      {VariantKind::MillimetreDepth, "mm-depth"},
      {VariantKind::Focal, "focal"},
      {VariantKind::Unregistered, "unregistered"},
      {VariantKind::MotionBlur, "blur"},
      {VariantKind::LowLight, "low-light"},
      {VariantKind::Burst, "burst"},
      {VariantKind::ThereAndBack, "there-and-back"},
      {VariantKind::Resolution, "resolution"},
      {VariantKind::DepthNoise, "depth-noise"},
      {VariantKind::DepthResolution, "depth-resolution"},
      {VariantKind::Crop, "crop"},
      {VariantKind::Exposure, "exposure"},
      {VariantKind::FrameStep, "frame-step"}};
  return names;
}

bool has(const SequenceVariantOptions& options, VariantKind kind) {
  return std::find(options.kinds.begin(), options.kinds.end(), kind) != options.kinds.end();
}

std::string timestampText(double timestamp) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.6f", timestamp);
  return text;
}

void require(bool condition, const std::string& what) {
  if (!condition) throw std::invalid_argument("sequence variant: " + what);
}

void checkOptions(const SequenceVariantOptions& options) {
  require(!options.kinds.empty(), "no variant kind given");
  require(options.jpeg_quality >= 1 && options.jpeg_quality <= 100, "JPEG quality must be in [1, 100]");
  require(options.depth_factor >= 100.0 && options.depth_factor <= 65535.0,
          "depth factor must be in [100, 65535] raw values per metre");
  require(options.depth_noise_coefficient >= 0.0 && options.depth_noise_coefficient <= 0.1,
          "depth noise coefficient must be in [0, 0.1] m per square metre");
  require(options.depth_noise_correlation_px >= 0.0 && options.depth_noise_correlation_px <= 50.0,
          "depth noise correlation must be in [0, 50] px");
  require(options.resolution_scale >= 0.25 && options.resolution_scale <= 4.0, "resolution scale must be in [0.25, 4]");
  require(options.depth_resolution_scale >= 0.25 && options.depth_resolution_scale <= 4.0,
          "depth resolution scale must be in [0.25, 4]");
  const auto at = [&](VariantKind kind) { return std::find(options.kinds.begin(), options.kinds.end(), kind); };
  require(options.crop_aspect >= 1.0 && options.crop_aspect <= 4.0, "crop aspect must be in [1, 4] (width / height)");
  require(options.exposure_stops >= 0.0 && options.exposure_stops <= 4.0, "exposure stops must be in [0, 4]");
  require(options.exposure_period_frames >= 2.0 && options.exposure_period_frames <= 10000.0,
          "exposure period must be in [2, 10000] frames");
  require(options.frame_step >= 1 && options.frame_step <= 30, "frame step must be in [1, 30]");
  // A crop cuts the colour camera's rows out of depth registered to it: before the depth has a camera of its own.
  for (const VariantKind kind : {VariantKind::Unregistered, VariantKind::DepthResolution})
    require(!has(options, VariantKind::Crop) || !has(options, kind) || at(VariantKind::Crop) < at(kind),
            "crop must come before " + toString(kind));
  if (has(options, VariantKind::DepthResolution)) {
    // The kinds that move or resize the depth image as the colour camera's come first: they assume its size.
    for (const VariantKind kind : {VariantKind::Focal, VariantKind::Resolution, VariantKind::Unregistered})
      require(at(kind) < at(VariantKind::DepthResolution) || !has(options, kind),
              "depth-resolution must come after " + toString(kind));
    require(!has(options, VariantKind::Unregistered) || options.describe_depth_camera,
            "depth-resolution needs the unregistered depth camera described in camera.yaml");
  }
  require(options.focal_length_px >= 50.0 && options.focal_length_px <= 5000.0,
          "focal length must be in [50, 5000] px");
  require(options.depth_offset_m.allFinite() && options.depth_offset_m.norm() <= 0.5,
          "the depth camera's offset must be finite and at most 0.5 m");
  require(std::abs(options.depth_rotation_deg) <= 10.0, "the depth camera's rotation must be within 10 degrees");
  require(options.blur_length_px >= 1.0 && options.blur_length_px <= 200.0, "blur length must be in [1, 200] px");
  require(options.burst_blur_length_px >= 1.0 && options.burst_blur_length_px <= 200.0,
          "burst blur length must be in [1, 200] px");
  require(options.low_light_gain > 0.0 && options.low_light_gain <= 1.0, "low-light gain must be in (0, 1]");
  require(options.low_light_gamma > 0.0 && options.low_light_gamma <= 10.0, "low-light gamma must be in (0, 10]");
  require(options.low_light_noise >= 0.0 && options.burst_noise_sigma >= 0.0, "noise sigmas must be >= 0");
  require(options.burst_length >= 1 && options.burst_period >= options.burst_length,
          "bursts need a length >= 1 and a period >= their length");
}

/// The unregistered depth camera of the variant: the colour camera's intrinsics, no distortion, its pose.
Eigen::Isometry3d depthInColor(const SequenceVariantOptions& options) {
  Eigen::Isometry3d depth_in_color = Eigen::Isometry3d::Identity();
  depth_in_color.linear() =
      Eigen::AngleAxisd(options.depth_rotation_deg * M_PI / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix();
  depth_in_color.translation() = options.depth_offset_m;
  return depth_in_color;
}

/// The camera with the unregistered variant's depth camera: the colour camera's intrinsics, no distortion, the
/// variant's pose.
PinholeCamera withDepthCamera(PinholeCamera camera, const SequenceVariantOptions& options) {
  DepthCamera depth{camera.fx, camera.fy, camera.cx, camera.cy, {}, {}};
  const Eigen::Isometry3d pose = depthInColor(options);
  const Eigen::AngleAxisd rotation(pose.linear());
  for (int i = 0; i < 3; ++i) {
    depth.translation_m[static_cast<std::size_t>(i)] = pose.translation()[i];
    depth.rotation_rad[static_cast<std::size_t>(i)] = rotation.angle() * rotation.axis()[i];
  }
  camera.unregistered_depth = depth;
  return camera;
}

/// The camera the variant is read with: the kinds that change it, in order. An unregistered variant's camera file
/// names its depth camera (as a real sensor's calibration would), so that the front end can register the depth.
PinholeCamera variantCamera(const PinholeCamera& original, const SequenceVariantOptions& options) {
  PinholeCamera camera = original;
  for (const VariantKind kind : options.kinds) {
    if (kind == VariantKind::Focal) camera = zoomedCamera(camera, options.focal_length_px / camera.fx);
    if (kind == VariantKind::Resolution) camera = resizedCamera(camera, options.resolution_scale);
    if (kind == VariantKind::MillimetreDepth) camera.depth_factor = options.depth_factor;
    if (kind == VariantKind::Unregistered && options.describe_depth_camera) camera = withDepthCamera(camera, options);
    if (kind == VariantKind::DepthResolution) camera = depthResizedCamera(camera, options.depth_resolution_scale);
    if (kind == VariantKind::Crop) camera = croppedCamera(camera, options.crop_aspect);
  }
  return camera;
}

/// The pose at `timestamp` between the two poses of the time-sorted `trajectory` around it, at most `max_gap`
/// seconds apart (the translation interpolated linearly, the rotation by slerp); none outside the trajectory's
/// span or across a larger gap in it.
std::optional<Eigen::Isometry3d> poseAt(const Trajectory& sorted, double timestamp, double max_gap = 0.1) {
  const auto after = std::lower_bound(sorted.begin(), sorted.end(), timestamp,
                                      [](const StampedPose& p, double t) { return p.timestamp < t; });
  if (after == sorted.end()) return std::nullopt;
  if (after->timestamp == timestamp) return after->pose;
  if (after == sorted.begin()) return std::nullopt;
  const StampedPose& before = *(after - 1);
  if (after->timestamp - before.timestamp > max_gap) return std::nullopt;
  const double s = (timestamp - before.timestamp) / (after->timestamp - before.timestamp);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = (1.0 - s) * before.pose.translation() + s * after->pose.translation();
  pose.linear() = Eigen::Quaterniond(before.pose.linear())
                      .slerp(s, Eigen::Quaterniond(after->pose.linear()))
                      .normalized()
                      .toRotationMatrix();
  return pose;
}

/// Burst k (0, 1, ...) covers frames start + k period ... + length - 1; even bursts blur, odd ones add noise.
const char* burstDegradation(std::size_t i, const SequenceVariantOptions& options) {
  if (i < options.burst_start) return nullptr;
  const std::size_t since = i - options.burst_start;
  if (since % options.burst_period >= options.burst_length) return nullptr;
  return (since / options.burst_period) % 2 == 0 ? "blur" : "noise";
}

/// Frame i changed by every kind in order; `camera` is the input camera, updated as the kinds change it.
RgbdFrame applyKinds(RgbdFrame frame, std::size_t i, PinholeCamera camera, const SequenceVariantOptions& options,
                     std::vector<DegradedFrame>& degraded) {
  // Each frame draws from its own stream: the output does not depend on what was written before.
  cv::RNG rng(options.seed * 0x9E3779B97F4A7C15ull + i + 1);
  for (const VariantKind kind : options.kinds) {
    switch (kind) {
      case VariantKind::Jpeg:
      case VariantKind::MillimetreDepth: break;  // how the images are written
      case VariantKind::ThereAndBack:            // the order of the frames: thereAndBack, before any frame
      case VariantKind::FrameStep: break;        // which frames: everyNthFrame, before thereAndBack
      case VariantKind::Exposure: frame.color = changeExposure(frame.color, exposureStops(i, options)); break;
      case VariantKind::Focal: {
        const double scale = options.focal_length_px / camera.fx;
        frame.color = zoomImage(frame.color, camera, scale, cv::INTER_LINEAR);
        frame.depth = zoomImage(frame.depth, camera, scale, cv::INTER_NEAREST);
        camera = zoomedCamera(camera, scale);
        break;
      }
      case VariantKind::Resolution:
        frame.color = resizeImage(frame.color, camera, options.resolution_scale, cv::INTER_AREA);
        frame.depth = resizeImage(frame.depth, camera, options.resolution_scale, cv::INTER_NEAREST);
        camera = resizedCamera(camera, options.resolution_scale);
        break;
      case VariantKind::Crop:
        frame.color = cropImage(frame.color, camera, options.crop_aspect);
        frame.depth = cropImage(frame.depth, camera, options.crop_aspect);
        camera = croppedCamera(camera, options.crop_aspect);
        break;
      case VariantKind::DepthNoise:
        frame.depth = noisyDepth(frame.depth, options.depth_noise_coefficient, options.depth_noise_correlation_px, rng);
        break;
      case VariantKind::Unregistered:
        frame.depth = unregisteredDepth(frame.depth, camera, depthInColor(options));
        if (options.describe_depth_camera) camera = withDepthCamera(camera, options);
        break;
      case VariantKind::DepthResolution:
        frame.depth = depthResizedImage(frame.depth, camera, options.depth_resolution_scale);
        camera = depthResizedCamera(camera, options.depth_resolution_scale);
        break;
      case VariantKind::MotionBlur:
        frame.color = motionBlur(frame.color, options.blur_length_px, rng.uniform(0.0, 180.0));
        break;
      case VariantKind::LowLight:
        frame.color =
            lowLight(frame.color, options.low_light_gain, options.low_light_gamma, options.low_light_noise, rng);
        break;
      case VariantKind::Burst: {
        const char* how = burstDegradation(i, options);
        if (!how) break;
        frame.color = std::string(how) == "blur"
                          ? motionBlur(frame.color, options.burst_blur_length_px, rng.uniform(0.0, 180.0))
                          : addGaussianNoise(frame.color, options.burst_noise_sigma, rng);
        degraded.push_back({i, frame.timestamp, how});
        break;
      }
    }
  }
  return frame;
}

/// Inside the AtomicFolder's temporary folder, so a plain write is already all or nothing.
void writeText(const fs::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  out.close();
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

void writeImage(const fs::path& path, const cv::Mat& image, const std::vector<int>& parameters = {}) {
  if (!cv::imwrite(path.string(), image, parameters)) throw std::runtime_error("cannot write " + path.string());
}

void writeDescription(const fs::path& path, const VariantSource& source, const SequenceVariantOptions& options) {
  std::ostringstream text;
  text << "# sequence variant (weighted_icp simulation/sequence_variants.h)\nsource: " << source.description
       << "\nkinds:";
  for (const VariantKind kind : options.kinds) text << ' ' << toString(kind);
  text << "\nseed: " << options.seed;
  if (has(options, VariantKind::Jpeg)) text << "\njpeg_quality: " << options.jpeg_quality;
  if (has(options, VariantKind::MillimetreDepth)) text << "\ndepth_factor: " << options.depth_factor;
  if (has(options, VariantKind::Focal)) text << "\nfocal_length_px: " << options.focal_length_px;
  if (has(options, VariantKind::Resolution)) text << "\nresolution_scale: " << options.resolution_scale;
  if (has(options, VariantKind::DepthResolution))
    text << "\ndepth_resolution_scale: " << options.depth_resolution_scale;
  if (has(options, VariantKind::Crop)) text << "\ncrop_aspect: " << options.crop_aspect;
  if (has(options, VariantKind::Exposure))
    text << "\nexposure_stops: " << options.exposure_stops
         << "\nexposure_period_frames: " << options.exposure_period_frames;
  if (has(options, VariantKind::FrameStep)) text << "\nframe_step: " << options.frame_step;
  if (has(options, VariantKind::DepthNoise))
    text << "\ndepth_noise_coefficient: " << options.depth_noise_coefficient
         << "\ndepth_noise_correlation_px: " << options.depth_noise_correlation_px;
  if (has(options, VariantKind::Unregistered))
    text << "\ndepth_offset_m: " << options.depth_offset_m.transpose()
         << "\ndepth_rotation_deg: " << options.depth_rotation_deg;
  if (has(options, VariantKind::MotionBlur)) text << "\nblur_length_px: " << options.blur_length_px;
  if (has(options, VariantKind::LowLight))
    text << "\nlow_light_gain: " << options.low_light_gain << "\nlow_light_gamma: " << options.low_light_gamma
         << "\nlow_light_noise: " << options.low_light_noise;
  if (has(options, VariantKind::Burst))
    text << "\nburst_start: " << options.burst_start << "\nburst_period: " << options.burst_period
         << "\nburst_length: " << options.burst_length << "\nburst_blur_length_px: " << options.burst_blur_length_px
         << "\nburst_noise_sigma: " << options.burst_noise_sigma;
  writeText(path, text.str() + "\n");
}

void writeDegradedFrames(const fs::path& path, const std::vector<DegradedFrame>& degraded) {
  std::ostringstream text;
  text << "# frames degraded by bursts: index (in rgb.txt order) timestamp blur|noise\n";
  for (const DegradedFrame& frame : degraded)
    text << frame.index << ' ' << timestampText(frame.timestamp) << ' ' << frame.how << '\n';
  writeText(path, text.str());
}

/// Every frame into `folder`: images and both lists.
std::vector<DegradedFrame> writeFrames(const VariantSource& source, const SequenceVariantOptions& options,
                                       const PinholeCamera& camera, const fs::path& folder,
                                       const std::function<void(std::size_t)>& frame_written) {
  fs::create_directory(folder / "rgb");
  fs::create_directory(folder / "depth");
  std::ofstream rgb_list(folder / "rgb.txt"), depth_list(folder / "depth.txt");
  rgb_list << "# color images\n# " << source.description << "\n# timestamp filename\n";
  depth_list << "# depth maps\n# " << source.description << "\n# timestamp filename\n";
  const bool jpeg = has(options, VariantKind::Jpeg);
  std::vector<DegradedFrame> degraded;
  for (std::size_t i = 0; i < source.size; ++i) {
    const RgbdFrame frame = applyKinds(source.load(i), i, source.camera, options, degraded);
    const std::string rgb_name = "rgb/" + timestampText(frame.timestamp) + (jpeg ? ".jpg" : ".png");
    const std::string depth_name = "depth/" + timestampText(source.depth_timestamp(i)) + ".png";
    writeImage(folder / rgb_name, frame.color,
               jpeg ? std::vector<int>{cv::IMWRITE_JPEG_QUALITY, options.jpeg_quality} : std::vector<int>{});
    writeImage(folder / depth_name, depthToRaw(frame.depth, camera.depth_factor));
    rgb_list << timestampText(frame.timestamp) << ' ' << rgb_name << '\n';
    depth_list << timestampText(source.depth_timestamp(i)) << ' ' << depth_name << '\n';
    if (frame_written) frame_written(i);
  }
  for (std::ofstream* list : {&rgb_list, &depth_list}) {
    list->close();
    if (!*list) throw std::runtime_error("cannot write the lists in " + folder.string());
  }
  return degraded;
}

}  // namespace

std::string toString(VariantKind kind) {
  for (const auto& [k, name] : kindNames())
    if (k == kind) return name;
  return "unknown";
}

VariantKind parseVariantKind(const std::string& name) {
  std::string accepted;
  for (const auto& [kind, text] : kindNames()) {
    if (name == text) return kind;
    accepted += (accepted.empty() ? "" : "|") + std::string(text);
  }
  throw std::invalid_argument("unknown variant '" + name + "' (expected " + accepted + ")");
}

std::vector<VariantKind> parseVariantKinds(const std::string& names) {
  std::vector<VariantKind> kinds;
  std::stringstream list(names);
  std::string name;
  while (std::getline(list, name, ',')) {
    const VariantKind kind = parseVariantKind(name);
    if (std::find(kinds.begin(), kinds.end(), kind) != kinds.end())
      throw std::invalid_argument("variant '" + name + "' given twice");
    kinds.push_back(kind);
  }
  if (kinds.empty()) throw std::invalid_argument("no variant given");
  return kinds;
}

VariantSource tumVariantSource(const std::string& directory, const PinholeCamera& camera) {
  auto sequence = std::make_shared<io::TumSequence>(io::TumSequence::open(directory));
  VariantSource source;
  source.camera = camera;
  source.size = sequence->size();
  source.load = [sequence, camera](std::size_t i) { return sequence->loadFrame(i, camera); };
  source.timestamp = [sequence](std::size_t i) { return sequence->frame(i).rgb_timestamp; };
  source.depth_timestamp = [sequence](std::size_t i) { return sequence->frame(i).depth_timestamp; };
  source.groundtruth = sequence->groundTruth();
  source.description = "TUM sequence " + directory;
  return source;
}

VariantSource syntheticVariantSource(const SyntheticRgbdOptions& options) {
  auto sequence = std::make_shared<SyntheticRgbdSequence>(options);
  VariantSource source;
  source.camera = options.camera;
  source.size = sequence->size();
  source.load = [sequence](std::size_t i) { return sequence->frame(i).rgbd; };
  source.timestamp = [sequence](std::size_t i) { return sequence->timestamp(i); };
  source.depth_timestamp = [sequence](std::size_t i) { return sequence->timestamp(i); };
  for (std::size_t i = 0; i < sequence->size(); ++i)
    source.groundtruth.push_back({sequence->timestamp(i), sequence->cameraToWorld(i)});
  source.description = "synthetic sequence, seed " + std::to_string(options.seed);
  return source;
}

VariantSource thereAndBack(const VariantSource& source) {
  if (source.size < 4) throw std::invalid_argument("there and back: the source needs at least 4 frames");
  std::vector<double> stamp(source.size);  // the source's colour timestamps
  for (std::size_t i = 0; i < source.size; ++i)
    stamp[i] = source.timestamp ? source.timestamp(i) : source.load(i).timestamp;
  // Output frame j shows source frame `index` at `timestamp`, its depth image `depth_offset` later, as in the source.
  struct Shown {
    std::size_t index;
    double timestamp, depth_offset;
  };
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < source.size; i += 2) order.push_back(i);
  const std::size_t forward = order.size();
  const std::size_t last_odd = source.size % 2 == 0 ? source.size - 1 : source.size - 2;
  for (std::size_t k = 0; k <= last_odd / 2; ++k) order.push_back(last_odd - 2 * k);
  const double interval = (stamp[order[forward - 1]] - stamp[0]) / static_cast<double>(forward - 1);
  auto shown = std::make_shared<std::vector<Shown>>();
  for (std::size_t j = 0; j < order.size(); ++j) {
    const std::size_t i = order[j];
    const double t = j < forward ? stamp[i] : shown->back().timestamp + interval;
    shown->push_back({i, t, source.depth_timestamp(i) - stamp[i]});
  }

  VariantSource result = source;
  result.size = shown->size();
  result.load = [source, shown](std::size_t j) {
    RgbdFrame frame = source.load(shown->at(j).index);
    frame.timestamp = shown->at(j).timestamp;
    return frame;
  };
  result.timestamp = [shown](std::size_t j) { return shown->at(j).timestamp; };
  result.depth_timestamp = [shown](std::size_t j) { return shown->at(j).timestamp + shown->at(j).depth_offset; };
  Trajectory sorted = source.groundtruth;
  std::sort(sorted.begin(), sorted.end(),
            [](const StampedPose& a, const StampedPose& b) { return a.timestamp < b.timestamp; });
  result.groundtruth.clear();
  for (const Shown& frame : *shown)
    if (const auto pose = poseAt(sorted, stamp[frame.index])) result.groundtruth.push_back({frame.timestamp, *pose});
  result.description = source.description + ", there and back";
  return result;
}

VariantSource everyNthFrame(const VariantSource& source, std::size_t step) {
  if (step == 0) throw std::invalid_argument("every n-th frame: the step must be at least 1");
  if (source.size == 0) throw std::invalid_argument("every n-th frame: the source has no frame");
  VariantSource result = source;
  result.size = (source.size + step - 1) / step;
  result.load = [source, step](std::size_t j) { return source.load(j * step); };
  if (source.timestamp) result.timestamp = [source, step](std::size_t j) { return source.timestamp(j * step); };
  result.depth_timestamp = [source, step](std::size_t j) { return source.depth_timestamp(j * step); };
  result.description = source.description + ", every " + std::to_string(step) + " frames";
  return result;
}

double exposureStops(std::size_t i, const SequenceVariantOptions& options) {
  // The phases depend on the seed only, so frame i's exposure does not depend on the frames before it.
  constexpr std::uint64_t kExposureStream = 1;  // this file's only stream of the simulators' random source
  const double slow_phase = 2.0 * M_PI * unitInterval(subSeed(options.seed, kExposureStream, 0));
  const double fast_phase = 2.0 * M_PI * unitInterval(subSeed(options.seed, kExposureStream, 1));
  const double t = 2.0 * M_PI * static_cast<double>(i) / options.exposure_period_frames;
  return options.exposure_stops * (0.6 * std::sin(t + slow_phase) + 0.4 * std::sin(t / 0.37 + fast_phase));
}

VariantSummary writeSequenceVariant(const VariantSource& original, const SequenceVariantOptions& options,
                                    const std::string& dir, bool overwrite,
                                    const std::function<void(std::size_t)>& frame_written) {
  checkOptions(options);
  if (original.size == 0) throw std::invalid_argument("sequence variant: the source has no frame");
  VariantSource source = original;
  if (has(options, VariantKind::FrameStep)) source = everyNthFrame(source, options.frame_step);
  if (has(options, VariantKind::ThereAndBack)) source = thereAndBack(source);
  VariantSummary summary;
  summary.camera = variantCamera(source.camera, options);
  summary.frames = source.size;
  io::AtomicFolder folder(dir, overwrite);  // refuses a non-empty dir before any frame is read
  summary.degraded = writeFrames(source, options, summary.camera, folder.path(), frame_written);
  io::saveCamera(summary.camera, (folder.path() / "camera.yaml").string());
  if (!source.groundtruth.empty())
    io::writeTrajectory(source.groundtruth, (folder.path() / "groundtruth.txt").string());
  writeDescription(folder.path() / "variant.txt", source, options);
  if (has(options, VariantKind::Burst)) writeDegradedFrames(folder.path() / "bursts.txt", summary.degraded);
  folder.publish();
  return summary;
}

std::vector<DegradedFrame> readDegradedFrames(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open");
  std::vector<DegradedFrame> frames;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    DegradedFrame frame;
    if (!(fields >> frame.index >> frame.timestamp >> frame.how) || (frame.how != "blur" && frame.how != "noise"))
      throw std::runtime_error(path + ":" + std::to_string(number) + ": expected 'index timestamp blur|noise', got '" +
                               line + "'");
    frames.push_back(frame);
  }
  return frames;
}

}  // namespace weighted_icp::simulation
