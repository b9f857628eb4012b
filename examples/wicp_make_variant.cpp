// wicp_make_variant: writes a variant of a TUM RGB-D sequence (or of the
// synthetic one) as another sensor or condition would record it, in the TUM
// layout with its camera.yaml, so that the front end's defaults can be checked
// on data they were not chosen on (issue #11). Run the result with
//   wicp_rgbd_slam --dataset OUT   (OUT/camera.yaml is picked up)

#include <iostream>
#include <limits>

#include <boost/program_options.hpp>

#include "tool_support.h"
#include "weighted_icp/io/camera.h"
#include "weighted_icp/simulation/sequence_variants.h"

namespace po = boost::program_options;
using namespace weighted_icp;

namespace {

/// Everything the command line sets.
struct VariantCommand {
  std::string dataset, camera_spec, out_dir, kinds;
  simulation::SequenceVariantOptions options;
  simulation::SyntheticRgbdOptions synthetic;
  double offset_x = simulation::SequenceVariantOptions{}.depth_offset_m.x();
  bool overwrite = false;
};

/// @brief The settings of each variant kind, in their own group of --help.
/// @param c where the values go
po::options_description kindOptions(VariantCommand& c) {
  po::options_description kinds("Settings of the kinds");
  // One option per line reads as a table: not reflowed.
  // clang-format off
  kinds.add_options()
      ("jpeg-quality", tools::rangedValue(&c.options.jpeg_quality, 1, 100)->default_value(c.options.jpeg_quality), "jpeg: quality (1-100)")
      ("depth-factor", tools::rangedValue(&c.options.depth_factor, 100.0, 65535.0)->default_value(c.options.depth_factor), "mm-depth: raw value per metre (100-65535)")
      ("focal", tools::rangedValue(&c.options.focal_length_px, 50.0, 5000.0)->default_value(c.options.focal_length_px), "focal: new fx in px (50-5000)")
      ("resolution-scale", tools::rangedValue(&c.options.resolution_scale, 0.25, 4.0)->default_value(c.options.resolution_scale), "resolution: new width / old, same field of view (0.25-4; 0.5: 640x480 becomes 320x240)")
      ("depth-resolution-scale", tools::rangedValue(&c.options.depth_resolution_scale, 0.25, 4.0)->default_value(c.options.depth_resolution_scale), "depth-resolution: depth width / colour width, same field of view (0.25-4; 0.5: 320x240 depth beside 640x480 colour)")
      ("crop-aspect", tools::rangedValue(&c.options.crop_aspect, 1.0, 4.0)->default_value(c.options.crop_aspect), "crop: width / height kept, the middle rows (1-4, at least the source's; 1.7778: 16:9, 640x480 becomes 640x360); before unregistered and depth-resolution")
      ("exposure-stops", tools::rangedValue(&c.options.exposure_stops, 0.0, 4.0)->default_value(c.options.exposure_stops), "exposure: most stops a frame is off (0-4; 1: between half and twice the light)")
      ("exposure-period", tools::rangedValue(&c.options.exposure_period_frames, 2.0, 10000.0)->default_value(c.options.exposure_period_frames), "exposure: frames of the slower swing (2-10000)")
      ("frame-step", tools::rangedValue(&c.options.frame_step, std::size_t{1}, std::size_t{30})->default_value(c.options.frame_step), "frame-step: keep every N-th frame (1-30; 2: 30 Hz becomes 15 Hz)")
      ("depth-noise", tools::rangedValue(&c.options.depth_noise_coefficient, 0.0, 0.1)->default_value(c.options.depth_noise_coefficient), "depth-noise: sigma = this z^2, metres (0-0.1; a Kinect v1 about 0.0015, a stereo camera 0.01)")
      ("depth-noise-correlation", tools::rangedValue(&c.options.depth_noise_correlation_px, 0.0, 50.0)->default_value(c.options.depth_noise_correlation_px), "depth-noise: errors correlated over this many px (0-50)")
      ("depth-offset", tools::rangedValue(&c.offset_x, -0.5, 0.5)->default_value(c.offset_x), "unregistered: depth camera x offset, m")
      ("depth-rotation", tools::rangedValue(&c.options.depth_rotation_deg, -10.0, 10.0)->default_value(c.options.depth_rotation_deg), "unregistered: rotation about y, degrees")
      ("no-depth-calibration", "unregistered: leave the depth camera out of camera.yaml (the front end then reads depth unregistered)")
      ("blur-length", tools::rangedValue(&c.options.blur_length_px, 1.0, 200.0)->default_value(c.options.blur_length_px), "blur: length in px (1-200)")
      ("gain", tools::rangedValue(&c.options.low_light_gain, 0.01, 1.0)->default_value(c.options.low_light_gain), "low-light: gain (0.01-1)")
      ("gamma", tools::rangedValue(&c.options.low_light_gamma, 0.1, 10.0)->default_value(c.options.low_light_gamma), "low-light: gamma (0.1-10)")
      ("noise", tools::rangedValue(&c.options.low_light_noise, 0.0, 100.0)->default_value(c.options.low_light_noise), "low-light: noise sigma, grey levels")
      ("burst-start", tools::rangedValue(&c.options.burst_start, std::size_t{0})->default_value(c.options.burst_start), "burst: first degraded frame")
      ("burst-period", tools::rangedValue(&c.options.burst_period, std::size_t{1})->default_value(c.options.burst_period), "burst: frames from one burst to the next")
      ("burst-length", tools::rangedValue(&c.options.burst_length, std::size_t{1})->default_value(c.options.burst_length), "burst: frames per burst")
      ("burst-blur", tools::rangedValue(&c.options.burst_blur_length_px, 1.0, 200.0)->default_value(c.options.burst_blur_length_px), "burst: blur length in px")
      ("burst-noise", tools::rangedValue(&c.options.burst_noise_sigma, 0.0, 100.0)->default_value(c.options.burst_noise_sigma), "burst: noise sigma, grey levels")
      ("seed", tools::rangedValue(&c.options.seed, std::uint64_t{0})->default_value(c.options.seed), "blur directions and noise");
  // clang-format on
  return kinds;
}

/// Parses and checks the command line into `c`; false when only --help was asked for.
bool parseCommand(int argc, char** argv, VariantCommand& c) {
  po::options_description description(
      "wicp_make_variant [--dataset DIR [--camera fr1|fr2|fr3|FILE.yaml]] --variant KIND[,KIND...] --out DIR\n"
      "Writes DIR in the TUM layout (rgb/, depth/, rgb.txt, depth.txt, groundtruth.txt) with camera.yaml,\n"
      "variant.txt and, for bursts, bursts.txt. Kinds, applied in the order given: jpeg, mm-depth, focal,\n"
      "unregistered, blur, low-light, burst, resolution, depth-noise, depth-resolution (a depth camera of\n"
      "its own size, after focal, resolution and unregistered), crop (the middle rows: another aspect ratio,\n"
      "before unregistered and depth-resolution), exposure (auto exposure: each frame's light changed smoothly);\n"
      "frame-step keeps every N-th frame (a lower frame rate) and there-and-back re-orders the frames, both before\n"
      "any other (even ones forward, then odd ones back: a real revisit). Without --dataset the synthetic\n"
      "sequence is used.\n"
      "Exit 1 on an error (nothing written), 2 on a bad command line. Options");
  // One option per line reads as a table: not reflowed.
  // clang-format off
  description.add_options()
      ("help,h", "print this help")
      ("dataset", po::value(&c.dataset), "TUM RGB-D folder; default: the synthetic sequence")
      ("camera", po::value(&c.camera_spec), "fr1, fr2, fr3 or a camera YAML; default: DIR/camera.yaml, else from the folder name")
      ("variant", po::value(&c.kinds)->required(), "comma-separated kinds (jpeg,mm-depth,focal,unregistered,blur,low-light,burst,there-and-back,resolution,depth-noise,depth-resolution,crop,exposure,frame-step)")
      ("out", po::value(&c.out_dir)->required(), "output folder (written complete or not at all)")
      ("overwrite", "replace --out if it exists and is not empty");
  // clang-format on
  description.add(kindOptions(c));
  // Their own group, so that --dataset refuses each of them.
  po::options_description synthetic_options("The synthetic sequence (without --dataset)");
  // clang-format off
  synthetic_options.add_options()
      ("synthetic-frames", tools::rangedValue(&c.synthetic.frames, std::size_t{1}, std::size_t{100000})->default_value(c.synthetic.frames), "frames (1-100000)")
      ("synthetic-seed", tools::rangedValue(&c.synthetic.seed, std::uint64_t{0})->default_value(c.synthetic.seed), "seed");
  // clang-format on
  description.add(synthetic_options);
  po::variables_map vm;
  if (!tools::parseCommandLine(argc, argv, description, vm)) return false;
  tools::requireOptionsOfTheSource(vm, !c.dataset.empty(), synthetic_options);
  c.overwrite = vm.count("overwrite") > 0;
  c.options.describe_depth_camera = vm.count("no-depth-calibration") == 0;
  try {
    c.options.kinds = simulation::parseVariantKinds(c.kinds);
  } catch (const std::invalid_argument& e) {
    throw po::error(std::string("--variant: ") + e.what());
  }
  if (c.options.burst_period < c.options.burst_length)
    tools::throwOutOfRange("burst-period", std::to_string(c.options.burst_period),
                           static_cast<long long>(c.options.burst_length), std::numeric_limits<long long>::max());
  c.options.depth_offset_m.x() = c.offset_x;
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  return tools::runTool("wicp_make_variant", [&] {
    VariantCommand c;
    if (!parseCommand(argc, argv, c)) return 0;
    const simulation::VariantSource source =
        c.dataset.empty() ? simulation::syntheticVariantSource(c.synthetic)
                          : simulation::tumVariantSource(c.dataset, io::datasetCamera(c.dataset, c.camera_spec));
    tools::Progress progress("writing", source.size);
    const simulation::VariantSummary summary = simulation::writeSequenceVariant(
        source, c.options, c.out_dir, c.overwrite, [&](std::size_t) { progress.step(); });
    progress.finish();
    std::cout << "wrote " << summary.frames << " frames (" << c.kinds << ") to " << c.out_dir << ": fx "
              << summary.camera.fx << ", depth factor " << summary.camera.depth_factor << ", "
              << summary.degraded.size() << " frames degraded by bursts\n";
    return 0;
  });
}
