// wicp_synthetic_rgbd: renders a synthetic RGB-D sequence with exact ground
// truth (a hand-held camera in a textured room) and writes it in the TUM
// RGB-D layout, so the front end can be run and scored without external data.

#include <chrono>
#include <cstdint>
#include <iomanip>
#include <iostream>
#include <stdexcept>

#include <boost/program_options.hpp>

#include "synthetic_scene_options.h"
#include "tool_support.h"
#include "weighted_icp/simulation/rgbd_sequence.h"
#include "weighted_icp/simulation/tum_export.h"

namespace po = boost::program_options;
using namespace weighted_icp;

int main(int argc, char** argv) {
  return tools::runTool("wicp_synthetic_rgbd", [&] {
    std::string out_dir;
    simulation::SyntheticRgbdOptions options;
    bool no_depth_noise = false, overwrite = false;
    po::options_description description(
        "wicp_synthetic_rgbd --out DIR [options]\n"
        "Renders a synthetic RGB-D sequence (TUM layout, exact ground truth). Options");
    // One option per line reads as a table: not reflowed.
    // clang-format off
    description.add_options()
        ("help,h", "print this help")
        ("out", po::value(&out_dir)->required(), "output folder (written complete or not at all)")
        ("frames", tools::rangedValue(&options.frames, std::size_t{1}, std::size_t{100000})->default_value(options.frames),
         "number of frames (1-100000)")
        ("seed", tools::rangedValue(&options.seed, std::uint64_t{0})->default_value(options.seed),
         "random seed (textures, path phases, noise)")
        ("fps", tools::positiveValue(&options.fps, 1e6)->default_value(options.fps), "frames per second (timestamps)")
        ("no-depth-noise", po::bool_switch(&no_depth_noise), "exact depth (up to the 16-bit resolution)")
        ("depth-noise-coefficient", tools::rangedValue(&options.depth_noise_coefficient, 0.0, 1.0)
                                        ->default_value(options.depth_noise_coefficient),
         "depth noise sigma = coefficient * z^2 (metres)")
        ("overwrite", po::bool_switch(&overwrite), "replace DIR if it exists and is not empty");
    // clang-format on
    tools::addSyntheticSceneOptions(description, options);
    po::variables_map vm;
    if (!tools::parseCommandLine(argc, argv, description, vm)) return 0;
    options.depth_noise = !no_depth_noise;

    const simulation::SyntheticRgbdSequence sequence(options);
    tools::Progress progress("rendering", sequence.size());
    const auto start = std::chrono::steady_clock::now();
    try {
      simulation::writeTumSequence(sequence, out_dir, overwrite, [&](std::size_t) { progress.step(); });
    } catch (...) {
      tools::rethrowWithOverwriteHint(overwrite);
    }
    progress.finish();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::cout << "wrote " << sequence.size() << " frames to " << out_dir << " (" << std::fixed << std::setprecision(1)
              << 1000.0 * seconds / sequence.size() << " ms per frame, rendering and PNG)\n";
    return 0;
  });
}
