// The synthetic scene's command-line options, defined once (see synthetic_scene_options.h).
#include "synthetic_scene_options.h"

#include "tool_support.h"

namespace weighted_icp::tools {

namespace po = boost::program_options;

void addSyntheticSceneOptions(po::options_description& description, simulation::SyntheticRgbdOptions& options,
                              const std::string& help_prefix) {
  const auto help = [&](const std::string& text) { return help_prefix + text; };
  // One option per line reads as a table: not reflowed.
  // clang-format off
  description.add_options()
      ("moving-object", po::bool_switch(&options.moving_object), help("a textured box moves through the view now and then").c_str())
      ("dim", po::bool_switch(&options.dim_lighting), help("dim, low-contrast, noisy images").c_str())
      ("frames-per-loop", rangedValue(&options.frames_per_loop, 10.0, 1e6)->default_value(options.frames_per_loop),
       help("frames to go once round; fewer than the frames rendered makes a loop (10-1e6)").c_str())
      ("depth-distortion", rangedValue(&options.depth_distortion, -0.1, 0.1)->default_value(options.depth_distortion),
       help("a fixed depth error, depth times 1 + D r^2 (r: distance from the image centre over the focal length), "
            "as a structured-light sensor's; the odometry drifts steadily (-0.1-0.1)").c_str())
      ("repeated-texture", po::bool_switch(&options.repeated_texture),
       help("every surface shows the same texture tile (perceptual aliasing)").c_str())
      ("room-scale", rangedValue(&options.room_scale, 1.0, 4.0)->default_value(options.room_scale),
       help("stretch the room's floor plan and the camera's path by this (farther, noisier walls; raise "
            "--frames-per-loop with it) (1-4)").c_str());
  // clang-format on
}

}  // namespace weighted_icp::tools
