// wicp_evaluate: the TUM RGB-D benchmark's trajectory errors of an estimated
// trajectory against ground truth, both in TUM format
// (timestamp tx ty tz qx qy qz qw): the absolute trajectory error as
// evaluate_ate.py and the relative pose error as evaluate_rpe.py --fixed_delta.
//
// Contract other tools rely on: with --json the last line of stdout is one
// JSON object with pairs, ate_rmse_m, ate_mean_m, ate_median_m, ate_max_m,
// alignment (4x4, estimate -> ground truth), rpe_pairs,
// rpe_translation_rmse_m, rpe_rotation_rmse_deg (and more); with --versus also
// versus_ate_rmse_m, common_poses, estimate_lower_fraction, error_correlation.

#include <iomanip>
#include <iostream>
#include <optional>
#include <sstream>

#include <boost/program_options.hpp>

#include "plotting.h"
#include "tool_support.h"
#include "weighted_icp/io/trajectory.h"
#include "weighted_icp/metrics/trajectory_error.h"

namespace po = boost::program_options;
using namespace weighted_icp;

namespace {
std::string metres(double value) {
  std::ostringstream text;
  text << std::fixed << std::setprecision(6) << value << " m (" << std::setprecision(2) << 100.0 * value << " cm)";
  return text.str();
}

std::string degrees(double value) {
  std::ostringstream text;
  text << std::fixed << std::setprecision(4) << value << " deg";
  return text.str();
}

void printStatistics(const char* label, const ErrorStatistics& s, std::string (*format)(double)) {
  std::cout << label << "  rmse " << format(s.rmse) << "  mean " << format(s.mean) << "  median " << format(s.median)
            << "  max " << format(s.max) << '\n';
}

/// Everything the command line sets.
struct EvaluateCommand {
  std::string groundtruth_path, estimate_path, rpe_unit_name = "s", plot_path, versus_path;
  double max_difference = 0.02, rpe_delta = 1.0;
  metrics::DeltaUnit rpe_unit = metrics::DeltaUnit::Seconds;
  bool json = false;
};

/// Parses and checks the command line into `c`; false when only --help was asked for.
bool parseCommand(int argc, char** argv, EvaluateCommand& c) {
  po::options_description options(
      "wicp_evaluate GROUNDTRUTH.txt ESTIMATE.txt [options]\n"
      "Absolute trajectory error and relative pose error of ESTIMATE against GROUNDTRUTH (TUM format). Options");
  // One option per line reads as a table: not reflowed.
  // clang-format off
  options.add_options()
      ("help,h", "print this help")
      ("groundtruth", po::value(&c.groundtruth_path)->required(), "ground-truth trajectory")
      ("estimate", po::value(&c.estimate_path)->required(), "estimated trajectory")
      ("max-difference", tools::positiveValue(&c.max_difference)->default_value(c.max_difference),
       "ATE: pair poses whose timestamps differ by less than this (seconds)")
      ("rpe-delta", tools::positiveValue(&c.rpe_delta)->default_value(c.rpe_delta), "RPE: compare poses this far apart")
      ("rpe-unit", po::value(&c.rpe_unit_name)->default_value(c.rpe_unit_name),
       "unit of --rpe-delta: s (seconds) or f (frames)")
      ("versus", po::value(&c.versus_path), "another estimate of the same frames: is ESTIMATE's ATE lower beyond "
                                            "the scatter of the poses? (a paired bootstrap over the poses both have)")
      ("json", "print the result as one JSON object on the last line of stdout")
      ("plot", po::value(&c.plot_path), "also draw both trajectories (top view, x/y/z against time) and the error "
                                        "along them into this PNG (needs matplotlib; a warning without it)");
  // clang-format on
  po::positional_options_description positional;
  positional.add("groundtruth", 1).add("estimate", 1);
  po::variables_map vm;
  if (!tools::parseCommandLine(argc, argv, options, vm, &positional)) return false;
  tools::requireOutputFolderOf(c.plot_path, "--plot");
  if (c.rpe_unit_name != "s" && c.rpe_unit_name != "f")
    throw po::validation_error(po::validation_error::invalid_option_value, "rpe-unit", c.rpe_unit_name);
  c.rpe_unit = c.rpe_unit_name == "s" ? metrics::DeltaUnit::Seconds : metrics::DeltaUnit::Frames;
  c.json = vm.count("json") > 0;
  return true;
}

/// The ATE, the RPE and the alignment, as text.
void printErrors(const EvaluateCommand& c, std::size_t groundtruth_poses, std::size_t estimate_poses,
                 const metrics::AbsoluteTrajectoryError& ate, const metrics::RelativePoseError& rpe) {
  std::cout << "ground truth " << groundtruth_poses << " poses, estimate " << estimate_poses << " poses, " << ate.pairs
            << " pairs within " << c.max_difference << " s\n";
  printStatistics("ATE", ate.translation, metres);
  std::cout << "RPE over " << rpe.pairs << " pose pairs " << c.rpe_delta
            << (c.rpe_unit == metrics::DeltaUnit::Seconds ? " s" : " frame(s)") << " apart\n";
  printStatistics("RPE translation", rpe.translation, metres);
  printStatistics("RPE rotation", rpe.rotation_deg, degrees);
  std::cout << "alignment (estimate -> ground truth):\n" << ate.alignment.matrix() << '\n';
}

/// --versus: which estimate's ATE is lower over resamples of the poses both have, as text.
void printVersus(const std::string& versus_path, const metrics::AteComparison& versus) {
  std::cout << "versus " << versus_path << ": over the " << versus.common_poses << " poses both have, ATE rmse "
            << metres(versus.first_rmse_m) << " against " << metres(versus.second_rmse_m) << "; lower in " << std::fixed
            << std::setprecision(1) << 100.0 * versus.first_lower_fraction << " % of " << versus.resamples
            << " resamples of the poses ("
            << (versus.first_lower_fraction >= 0.95   ? "lower beyond the scatter"
                : versus.first_lower_fraction <= 0.05 ? "higher beyond the scatter"
                                                      : "no difference the poses can show")
            << "); per-pose errors correlate " << std::setprecision(2) << versus.error_correlation << '\n';
}

/// The --json line (the contract in this file's header).
tools::JsonObject jsonReport(const EvaluateCommand& c, std::size_t groundtruth_poses, std::size_t estimate_poses,
                             const metrics::AbsoluteTrajectoryError& ate, const metrics::RelativePoseError& rpe,
                             const std::optional<metrics::AteComparison>& versus) {
  tools::JsonObject json;
  json.add("groundtruth_poses", groundtruth_poses)
      .add("estimate_poses", estimate_poses)
      .add("max_difference", c.max_difference)
      .add("pairs", ate.pairs)
      .add("ate_rmse_m", ate.translation.rmse)
      .add("ate_mean_m", ate.translation.mean)
      .add("ate_median_m", ate.translation.median)
      .add("ate_max_m", ate.translation.max)
      .add("alignment", Eigen::MatrixXd(ate.alignment.matrix()))
      .add("rpe_delta", c.rpe_delta)
      .add("rpe_unit", c.rpe_unit_name)
      .add("rpe_pairs", rpe.pairs)
      .add("rpe_translation_rmse_m", rpe.translation.rmse)
      .add("rpe_translation_mean_m", rpe.translation.mean)
      .add("rpe_translation_median_m", rpe.translation.median)
      .add("rpe_translation_max_m", rpe.translation.max)
      .add("rpe_rotation_rmse_deg", rpe.rotation_deg.rmse)
      .add("rpe_rotation_mean_deg", rpe.rotation_deg.mean)
      .add("rpe_rotation_median_deg", rpe.rotation_deg.median)
      .add("rpe_rotation_max_deg", rpe.rotation_deg.max);
  if (versus)
    json.add("versus_ate_rmse_m", versus->second.translation.rmse)
        .add("common_poses", versus->common_poses)
        .add("estimate_lower_fraction", versus->first_lower_fraction)
        .add("error_correlation", versus->error_correlation);
  return json;
}

}  // namespace

int main(int argc, char** argv) {
  return tools::runTool("wicp_evaluate", [&] {
    EvaluateCommand c;
    if (!parseCommand(argc, argv, c)) return 0;
    const Trajectory groundtruth = io::readTrajectory(c.groundtruth_path);
    const Trajectory estimate = io::readTrajectory(c.estimate_path);
    const metrics::AbsoluteTrajectoryError ate = metrics::computeAte(groundtruth, estimate, c.max_difference);
    const metrics::RelativePoseError rpe = metrics::computeRpe(groundtruth, estimate, c.rpe_delta, c.rpe_unit);
    printErrors(c, groundtruth.size(), estimate.size(), ate, rpe);
    std::optional<metrics::AteComparison> versus;
    if (!c.versus_path.empty()) {
      versus = metrics::compareAte(groundtruth, estimate, io::readTrajectory(c.versus_path), c.max_difference);
      printVersus(c.versus_path, *versus);
    }
    if (c.json) std::cout << jsonReport(c, groundtruth.size(), estimate.size(), ate, rpe, versus).str() << std::endl;
    if (!c.plot_path.empty())
      tools::plotTrajectory("wicp_evaluate", groundtruth, estimate, ate.alignment, c.max_difference, c.plot_path,
                            c.estimate_path + " against " + c.groundtruth_path);
    return 0;
  });
}
