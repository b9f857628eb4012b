#pragma once
// Variants of an RGB-D sequence as other sensors and conditions would record
// it (JPEG colour, depth in millimetres, another focal length, unregistered
// depth, motion blur, low light, bursts of bad frames, other resolutions and
// aspect ratios, auto exposure, a lower frame rate) or as a camera that
// comes back would (there and back), written in the TUM layout with a
// camera.yaml, so that a default chosen on one sequence can be checked on
// others (issues #11 and #6).

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "weighted_icp/core/camera.h"
#include "weighted_icp/core/rgbd_frame.h"
#include "weighted_icp/io/trajectory.h"
#include "weighted_icp/io/tum_sequence.h"
#include "weighted_icp/simulation/rgbd_sequence.h"

namespace weighted_icp::simulation {

/// @brief One change a variant makes; a variant applies several in order.
enum class VariantKind {
  Jpeg,             // colour written as JPEG (rgb/*.jpg) at jpeg_quality
  MillimetreDepth,  // depth written with depth_factor (1000: millimetres) and a camera file saying so
  Focal,            // zoomed about the principal point to focal_length_px
  Unregistered,     // depth seen from a depth camera offset from the colour camera
  MotionBlur,       // every colour image blurred along a random direction
  LowLight,         // every colour image darkened, gamma-crushed and noisy
  Burst,            // bursts of blurred or noisy colour frames (listed in bursts.txt)
  ThereAndBack,     // the frames re-ordered before any other kind: even ones forward, odd ones back (thereAndBack)
  Resolution,       // another sensor resolution, same field of view: images and camera resized by resolution_scale
  DepthNoise,       // noisier depth: z + depth_noise_coefficient z^2 n, n correlated over depth_noise_correlation_px
  DepthResolution,  // a depth camera of another resolution than the colour camera's (depth_resolution_scale), named
                    // in camera.yaml with its own size (depth_width, depth_height); after focal, resolution and
                    // unregistered
  Crop,             // another aspect ratio: the middle rows of colour and depth (crop_aspect, e.g. 16:9), same
                    // pixels and lens; before unregistered and depth-resolution
  Exposure,         // the exposure changing from frame to frame, as auto exposure does (exposureStops)
  FrameStep         // a lower frame rate: every frame_step-th frame (everyNthFrame), before there-and-back
};

/// @brief "jpeg", "mm-depth", "focal", "unregistered", "blur", "low-light", "burst", "there-and-back", "resolution",
/// "depth-noise", "depth-resolution", "crop", "exposure", "frame-step".
/// @param kind the kind to name
std::string toString(VariantKind kind);
/// @brief The kind of a name written by toString; std::invalid_argument naming the
/// accepted names otherwise.
/// @param name the name
VariantKind parseVariantKind(const std::string& name);
/// @brief Kinds from "jpeg,mm-depth,focal" (comma-separated, each once).
/// @param names the list; empty or repeated names throw std::invalid_argument
std::vector<VariantKind> parseVariantKinds(const std::string& names);

/// @brief The parameters of every kind; each is read only when its kind is applied.
struct SequenceVariantOptions {
  std::vector<VariantKind> kinds;
  int jpeg_quality = 75;
  /// Raw depth value per metre: 1000 for millimetres (TUM: 5000).
  double depth_factor = 1000.0;
  /// The new horizontal focal length; fy is scaled by the same factor.
  double focal_length_px = 585.0;
  /// Resolution: new width / old (0.5: 640x480 becomes 320x240), in [0.25, 4].
  double resolution_scale = 0.5;
  /// Depth resolution: new depth width / colour width, in [0.25, 4] (0.5: 320x240 depth beside 640x480 colour).
  double depth_resolution_scale = 0.5;
  /// Crop: width / height of the cropped images, in [the source's, 4] (16 / 9: 640x480 becomes 640x360).
  double crop_aspect = 16.0 / 9.0;
  /// Exposure: the most stops a frame's exposure is off (1: between half and twice the light), in [0, 4], and the
  /// period in frames of its slower swing (a faster one has 0.37 of it), in [2, 10000].
  double exposure_stops = 1.0;
  double exposure_period_frames = 30.0;
  /// Frame step: keep every frame_step-th frame (2: a 30 Hz sequence at 15 Hz), in [1, 30].
  std::size_t frame_step = 2;
  /// Depth noise: sigma = coefficient z^2 (m); 0.01 is a consumer stereo depth camera's (2 % at 2 m), several times
  /// a Kinect v1's. Its errors are correlated over about correlation_px pixels.
  double depth_noise_coefficient = 0.01;
  double depth_noise_correlation_px = 2.0;
  /// The depth camera's position in the colour camera's frame (a Kinect's IR
  /// camera sits about 2.5 cm beside its colour camera) and its rotation about y.
  Eigen::Vector3d depth_offset_m{0.025, 0.0, 0.0};
  double depth_rotation_deg = 0.5;
  /// Unregistered: camera.yaml names the depth camera (PinholeCamera::unregistered_depth), as a real sensor's
  /// calibration does, so the front end registers the depth; false writes the depth without its calibration.
  bool describe_depth_camera = true;
  double blur_length_px = 9.0;
  double low_light_gain = 0.3;
  double low_light_gamma = 1.3;
  double low_light_noise = 3.0;
  /// Bursts of burst_length frames start at burst_start and then every burst_period
  /// frames; they alternate blur (burst_blur_length_px) and noise (burst_noise_sigma).
  std::size_t burst_start = 8;
  std::size_t burst_period = 12;
  std::size_t burst_length = 2;
  double burst_blur_length_px = 15.0;
  double burst_noise_sigma = 15.0;
  /// Drives blur directions and noise: frame i draws from seed and i only.
  std::uint64_t seed = 1;
};

/// @brief A frame degraded by a burst: its index in the variant and how.
struct DegradedFrame {
  std::size_t index = 0;
  double timestamp = 0.0;
  std::string how;  // "blur" or "noise"
};

/// @brief What a variant was made from: frames (metric depth), their camera and
/// ground truth. Depth timestamps are kept so the written lists associate as the
/// original did.
struct VariantSource {
  PinholeCamera camera;
  std::size_t size = 0;
  std::function<RgbdFrame(std::size_t)> load;
  /// The colour image's timestamp of frame i (load(i).timestamp, without loading it).
  std::function<double(std::size_t)> timestamp;
  std::function<double(std::size_t)> depth_timestamp;
  Trajectory groundtruth;
  std::string description;
};

/// @brief A TUM folder read with `camera` (its depth_factor, its size).
/// @param directory the TUM folder (io::TumSequence::open's errors)
/// @param camera the folder's camera
VariantSource tumVariantSource(const std::string& directory, const PinholeCamera& camera);
/// @brief The synthetic sequence (rendered frame by frame as the variant is written).
/// @param options what to render
VariantSource syntheticVariantSource(const SyntheticRgbdOptions& options);

/// @brief A real revisit made from a sequence that never comes back: its even frames forward, then its odd frames
/// backwards, so the camera returns to its start over places it saw, through images it did not (each a frame
/// beside the one seen). The way back is timed after the last forward frame at the forward part's mean frame
/// interval (each depth image keeps its offset from its colour image); the ground truth is the original's,
/// interpolated at each frame's original timestamp (a frame outside it gets none).
/// @param source the sequence; fewer than 4 frames throw std::invalid_argument
VariantSource thereAndBack(const VariantSource& source);

/// @brief The sequence at a lower frame rate: frames 0, step, 2 step, ... with their timestamps, depth timestamps
/// and the whole ground truth (poses are associated by timestamp).
/// @param source the sequence
/// @param step frames from one kept frame to the next, >= 1; a source with no frame throws std::invalid_argument
VariantSource everyNthFrame(const VariantSource& source, std::size_t step);

/// @brief The exposure variant's change for frame i, in stops: two sinusoids (periods exposure_period_frames and
/// 0.37 of it, weights 0.6 and 0.4, phases drawn from the seed), times exposure_stops: smooth, as auto exposure
/// follows the scene, never more than exposure_stops off.
/// @param i the frame's index in the variant
/// @param options exposure_stops, exposure_period_frames and seed are read
double exposureStops(std::size_t i, const SequenceVariantOptions& options);

/// @brief What writeSequenceVariant wrote.
struct VariantSummary {
  PinholeCamera camera;  // also in camera.yaml
  std::size_t frames = 0;
  std::vector<DegradedFrame> degraded;  // also in bursts.txt
};

/// @brief Applies the options' kinds to every frame and writes the result in the
/// TUM layout: rgb/ (PNG, or JPEG), depth/ (16-bit PNG at the camera's
/// depth_factor), rgb.txt, depth.txt (the original timestamps), groundtruth.txt,
/// camera.yaml (the camera to read it with: `wicp_rgbd_slam --camera DIR/camera.yaml`),
/// variant.txt (what was done, with every parameter) and, with bursts, bursts.txt.
/// Written through io::AtomicFolder: complete or not at all.
/// @param source the sequence to change
/// @param options kinds and parameters; invalid ones throw std::invalid_argument
/// @param dir the folder to write; a non-empty one is refused unless `overwrite`
/// @param overwrite replace a non-empty `dir`
/// @param frame_written called with i after each frame, for progress
VariantSummary writeSequenceVariant(const VariantSource& source, const SequenceVariantOptions& options,
                                    const std::string& dir, bool overwrite = false,
                                    const std::function<void(std::size_t)>& frame_written = {});

/// @brief Reads a variant's bursts.txt ("index timestamp blur|noise" lines).
/// Throws std::runtime_error naming the file and line of a malformed line.
/// @param path the file
std::vector<DegradedFrame> readDegradedFrames(const std::string& path);

}  // namespace weighted_icp::simulation
