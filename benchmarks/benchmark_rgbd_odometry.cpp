// Accuracy and speed of the front end next to OpenCV's own RGB-D odometry
// (cv::rgbd::RgbdOdometry, frame to frame, default parameters) on the same
// frames: ATE RMSE (rigid alignment, as the TUM benchmark) and ms per frame.
//
//   wicp_benchmark_rgbd_odometry [--data DIR] [--synthetic-frames N]
//
// Runs tum_fr1_xyz_head and tum_fr3_teddy_head from DIR (default: the shared
// data set) and the project's synthetic sequence, static and with a moving
// object. Prints a Markdown table.

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <functional>
#include <iomanip>
#include <iostream>
#include <string>
#include <vector>

#include <boost/program_options.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/rgbd.hpp>

#include "rgbd_odometry_runs.h"
#include "weighted_icp/frontend/slam/rgbd_slam.h"
#include "weighted_icp/io/trajectory.h"
#include "weighted_icp/io/tum_sequence.h"
#include "weighted_icp/metrics/trajectory_error.h"
#include "weighted_icp/simulation/rgbd_sequence.h"

namespace po = boost::program_options;
using namespace weighted_icp;
using benchmarks::Sequence;

namespace {

Sequence loadTum(const std::string& dir, const std::string& name, int freiburg) {
  const io::TumSequence tum = io::TumSequence::open(dir);
  Sequence sequence{name, tumCamera(freiburg), {}, tum.groundTruth()};
  for (std::size_t i = 0; i < tum.size(); ++i) {
    sequence.frames.push_back(tum.loadFrame(i, sequence.camera));
  }
  return sequence;
}

Sequence makeSynthetic(std::size_t frames, bool moving_object) {
  simulation::SyntheticRgbdOptions options;
  options.frames = frames;
  options.moving_object = moving_object;
  const simulation::SyntheticRgbdSequence synthetic(options);
  Sequence sequence{moving_object ? "synthetic, moving object" : "synthetic", options.camera, {}, {}};
  for (std::size_t i = 0; i < synthetic.size(); ++i) {
    simulation::SyntheticRgbdFrame frame = synthetic.frame(i);
    sequence.truth.push_back({frame.rgbd.timestamp, frame.camera_to_world});
    sequence.frames.push_back(std::move(frame.rgbd));
  }
  return sequence;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    std::string data = WEIGHTED_ICP_DATA_DIR;
    std::size_t synthetic_frames = 150;
    po::options_description options("wicp_benchmark_rgbd_odometry options");
    options.add_options()("help,h", "print this help")("data", po::value(&data)->default_value(data),
                                                       "folder with tum_fr1_xyz_head and tum_fr3_teddy_head")(
        "synthetic-frames", po::value(&synthetic_frames)->default_value(synthetic_frames), "synthetic sequence length");
    po::variables_map vm;
    po::store(po::parse_command_line(argc, argv, options), vm);
    if (vm.count("help")) {
      std::cout << options << '\n';
      return 0;
    }
    po::notify(vm);

    std::vector<std::function<Sequence()>> sequences;
    for (const auto& [folder, freiburg] :
         {std::pair<const char*, int>{"tum_fr1_xyz_head", 1}, {"tum_fr3_teddy_head", 3}}) {
      const std::string dir = data + "/" + folder;
      if (std::filesystem::exists(dir))
        sequences.push_back([=] { return loadTum(dir, folder, freiburg); });
      else
        std::cerr << "skipping " << dir << ": not found\n";
    }
    sequences.push_back([=] { return makeSynthetic(synthetic_frames, false); });
    sequences.push_back([=] { return makeSynthetic(synthetic_frames, true); });

    std::cout << "| sequence | frames | ATE RMSE, ours (cm) | ATE RMSE, cv::rgbd::RgbdOdometry (cm) | median ms/frame, "
                 "ours | "
                 "median ms/frame, RgbdOdometry |\n|---|---|---|---|---|---|\n"
              << std::fixed;
    for (const auto& make : sequences) {
      const Sequence sequence = make();
      const benchmarks::Run ours = benchmarks::runFrontend(sequence);
      const benchmarks::Run opencv = benchmarks::runOpenCvOdometry(sequence);
      std::cout << "| " << sequence.name << " | " << sequence.frames.size() << " | " << std::setprecision(2)
                << ours.ate_rmse_m * 100 << " | " << opencv.ate_rmse_m * 100 << " | " << std::setprecision(1)
                << ours.medianMs() << " | " << opencv.medianMs() << " |" << std::endl;
    }
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "wicp_benchmark_rgbd_odometry: error: " << e.what() << '\n';
    return 1;
  }
}
