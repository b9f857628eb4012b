// wicp_align: aligns a source landmark map onto a target one with the
// confidence-weighted ICP (or plain PCL ICP with --strategy base).
//
// Contract other tools rely on: with --json the last line of stdout is one
// JSON object with transformation (4x4, as 4 rows), fitness_score,
// iterations, converged, degenerate (+ reason), correspondences and time_ms
// (alignment only). Exit codes: 0 converged, 1 error, 2 bad command line,
// 3 not converged, 4 degenerate problem (ICP not run).

#include <iomanip>
#include <iostream>

#include <boost/program_options.hpp>

#include "plotting.h"
#include "tool_support.h"
#include "weighted_icp/io/map_format.h"
#include "weighted_icp/registration/global_landmark_alignment.h"
#include "weighted_icp/registration/landmark_alignment.h"
#include "weighted_icp/registration/rigid_motion.h"

namespace po = boost::program_options;
using namespace weighted_icp;

int main(int argc, char** argv) {
  return tools::runTool("wicp_align", [&] {
    std::string source_path, target_path, strategy_name = "covariance", displacement_text, plot_path;
    AlignmentSettings settings;
    std::size_t min_observations = 2;
    bool global = false;
    bool pcl_stopping_only = false;
    po::options_description options(
        "wicp_align --source A.txt --target B.txt [options]\n"
        "Aligns landmark map A onto B (paper map format).\n"
        "Exit status: 0 converged, 1 error, 2 bad command line, 3 ICP did not converge, 4 degenerate problem\n"
        "(fewer than 3 landmarks, all identical or collinear, or k at least the target's landmarks: not run).\n"
        "Options");
    // One option per line reads as a table: not reflowed.
    // clang-format off
    options.add_options()
        ("help,h", "print this help")
        ("source", po::value(&source_path)->required(), "source map (moved onto the target)")
        ("target", po::value(&target_path)->required(), "target map")
        ("strategy", po::value(&strategy_name)->default_value(strategy_name),
         "weight strategy: base (plain PCL ICP), covariance, observations, mean-distance")
        ("k", tools::rangedValue(&settings.k, 1u, 1000u)->default_value(settings.k),
         "neighbours among which the heaviest is chosen (1-1000)")
        ("displace", po::value(&displacement_text),
         "move the source first: \"x y z roll pitch yaw\" (metres, degrees; R = Rz(yaw) Ry(pitch) Rx(roll))")
        ("max-iterations", tools::rangedValue(&settings.max_iterations, 1, 1000000)->default_value(settings.max_iterations),
         "ICP iteration limit (per stage)")
        ("max-correspondence-distance", tools::positiveValue(&settings.max_correspondence_distance),
         "ignore pairs farther apart than this (metres); default: no limit")
        ("min-observations", tools::rangedValue(&min_observations, std::size_t{0}, std::size_t{1000000})
                                 ->default_value(min_observations),
         "drop landmarks observed fewer times (the paper uses 2)")
        ("refine", po::bool_switch(&settings.refine), "finish with nearest-neighbour ICP after the weighted stage")
        ("no-stop-rule", po::bool_switch(&pcl_stopping_only),
         "stop on PCL's convergence criteria only (by default a stage also stops when its correspondences repeat "
         "the previous iteration's: same pose to float rounding, fewer iterations; docs/performance.md)")
        ("global", po::bool_switch(&global), "find the start from geometry alone, any yaw and translation, partial "
                                              "overlap allowed (docs/global_alignment.md); implies --refine")
        ("threads", tools::rangedValue(&settings.threads, 0u, 1024u)->default_value(settings.threads),
         "search threads, 0 = all (at most 1024)")
        ("json", "print the result as one JSON object on the last line of stdout")
        ("plot", po::value(&plot_path), "also draw the clouds before and after, top view, target coloured by weight, "
                                        "into this PNG (needs matplotlib; a warning without it)");
    // clang-format on
    po::variables_map vm;
    if (!tools::parseCommandLine(argc, argv, options, vm)) return 0;

    settings.stop_on_repeated_correspondences = !pcl_stopping_only;
    const WeightStrategy strategy = parseWeightStrategy(strategy_name);
    settings.k = neighboursFor(strategy, settings.k);
    const Displacement displacement =
        displacement_text.empty() ? Displacement{} : Displacement::parse(displacement_text);

    LandmarkMap source = io::readLandmarkMap(source_path).withMinObservations(min_observations);
    const LandmarkMap target = io::readLandmarkMap(target_path).withMinObservations(min_observations);
    if (source.landmarks.empty())
      throw std::runtime_error(source_path + ": no landmark with at least " + std::to_string(min_observations) +
                               " observations");
    if (target.landmarks.empty())
      throw std::runtime_error(target_path + ": no landmark with at least " + std::to_string(min_observations) +
                               " observations");
    source.transform(displacement.toIsometry());

    const WeightFunction weight = weightFunction(strategy);
    AlignmentResult result;
    if (global) {
      settings.refine = true;
      GlobalLandmarkAligner aligner({}, settings);
      aligner.setTarget(toLandmarkCloud(target, weight));
      const GlobalLandmarkAlignmentResult both = aligner.align(toLandmarkCloud(source, weight));
      result = both.alignment;
      std::cout << "global search: " << both.global.hypotheses_refined << " hypotheses refined, inlier fraction "
                << both.global.inlier_fraction << ", distance limit " << both.global.distance_limit << " m\n";
    } else {
      LandmarkAligner aligner(settings);
      aligner.setTarget(toLandmarkCloud(target, weight));
      result = aligner.align(toLandmarkCloud(source, weight));
    }

    std::cout << "source " << source.landmarks.size() << " landmarks, target " << target.landmarks.size()
              << " landmarks, strategy " << toString(strategy) << ", k " << settings.k << '\n'
              << (result.degenerate ? "degenerate: " + result.reason + "; not aligned\n" : std::string())
              << "converged " << (result.converged ? "yes" : "no") << " after " << result.iterations << " iterations";
    if (settings.refine) std::cout << " + " << result.refine_iterations << " refinement";
    std::cout << ", fitness score " << result.fitness_score << ", " << result.correspondences << " correspondences, "
              << std::fixed << std::setprecision(1) << result.time_ms << " ms\n"
              << std::defaultfloat << "transformation (source -> target):\n"
              << result.transformation << '\n';
    if (vm.count("json")) {
      tools::JsonObject json;
      json.add("transformation", Eigen::MatrixXd(result.transformation))
          .add("fitness_score", result.fitness_score)
          .add("iterations", result.iterations)
          .add("refine_iterations", result.refine_iterations)
          .add("converged", result.converged)
          .add("degenerate", result.degenerate);
      if (result.degenerate) json.add("reason", result.reason);
      json.add("correspondences", result.correspondences)
          .add("time_ms", result.time_ms)
          .add("strategy", toString(strategy))
          .add("k", static_cast<std::size_t>(settings.k))
          .add("source_landmarks", source.landmarks.size())
          .add("target_landmarks", target.landmarks.size());
      std::cout << json.str() << std::endl;
    }
    if (!plot_path.empty())
      tools::plotAlignment(
          "wicp_align", source, target, weight, result.transformation, plot_path,
          source_path + " onto " + target_path + " (" + toString(strategy) + ", k " + std::to_string(settings.k) + ")");
    if (result.degenerate) return 4;
    return result.converged ? 0 : 3;
  });
}
