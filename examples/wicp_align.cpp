// wicp_align: aligns a source landmark map onto a target one with the
// confidence-weighted ICP (or plain PCL ICP with --strategy base).
//
// Contract other tools rely on: with --json the last line of stdout is one
// JSON object with transformation (4x4, as 4 rows), fitness_score,
// iterations, converged, stopped_at_iteration_limit, degenerate (+ reason),
// correspondences and time_ms (alignment only); with --global also up_axis_source, up_axis_target and reversed
// (the search and the weighted ICP ran the target onto a source much larger than it: fitness_score
// and correspondences are then the target's). Exit codes: 0 converged, 1
// error, 2 bad command line, 3 not converged (or stopped at the iteration
// limit before its criteria were met), 4 degenerate problem (ICP not run).

#include <iomanip>
#include <iostream>

#include <boost/program_options.hpp>

#include "plotting.h"
#include "tool_support.h"
#include "up_axis_option.h"
#include "weighted_icp/io/map_format.h"
#include "weighted_icp/registration/global_landmark_alignment.h"
#include "weighted_icp/registration/landmark_alignment.h"
#include "weighted_icp/registration/rigid_motion.h"

namespace po = boost::program_options;
using namespace weighted_icp;

namespace {

/// @brief What the command line asks for.
struct AlignCommand {
  std::string source_path, target_path, strategy_name = "covariance", displacement_text, plot_path;
  std::string up_axis_text = "auto";
  tools::UpAxisOption up_axis;  // --up-axis, parsed with the command line
  AlignmentSettings settings;
  std::size_t min_observations = 2;
  bool global = false;
  bool pcl_stopping_only = false;
  bool json = false;
  WeightStrategy strategy = WeightStrategy::Covariance;
  Displacement displacement;  // --displace, parsed with the command line
};

/// @brief The two maps as aligned: the source already displaced.
struct AlignInputs {
  LandmarkMap source, target;
};

void interpretCommand(const po::variables_map& vm, AlignCommand& c);

/// @brief Parses the command line; false when only --help was asked for.
bool parseCommand(int argc, char** argv, AlignCommand& c) {
  po::options_description options(
      "wicp_align --source A.txt --target B.txt [options]\n"
      "Aligns landmark map A onto B (paper map format).\n"
      "Exit status: 0 converged, 1 error, 2 bad command line, 3 ICP did not converge (or stopped at --max-iterations "
      "before its criteria were met), 4 degenerate problem\n"
      "(fewer than 3 landmarks, all identical or collinear, or k at least the target's landmarks: not run).\n"
      "Options");
  // One option per line reads as a table: not reflowed.
  // clang-format off
  options.add_options()
      ("help,h", "print this help")
      ("source", po::value(&c.source_path)->required(), "source map (moved onto the target)")
      ("target", po::value(&c.target_path)->required(), "target map")
      ("strategy", po::value(&c.strategy_name)->default_value(c.strategy_name),
       "weight strategy: base (plain PCL ICP), covariance, observations, mean-distance")
      ("k", tools::rangedValue(&c.settings.k, 1u, 1000u)->default_value(c.settings.k),
       "neighbours among which the heaviest is chosen (1-1000)")
      ("displace", po::value(&c.displacement_text),
       "move the source first: \"x y z roll pitch yaw\" (metres, degrees; R = Rz(yaw) Ry(pitch) Rx(roll))")
      ("max-iterations", tools::rangedValue(&c.settings.max_iterations, 1, 1000000)->default_value(c.settings.max_iterations),
       "ICP iteration limit (per stage)")
      ("max-correspondence-distance", tools::positiveValue(&c.settings.max_correspondence_distance),
       "ignore pairs farther apart than this (metres); default: no limit")
      ("min-observations", tools::rangedValue(&c.min_observations, std::size_t{0}, std::size_t{1000000})
                               ->default_value(c.min_observations),
       "drop landmarks observed fewer times (the paper uses 2)")
      ("refine", po::bool_switch(&c.settings.refine), "finish with nearest-neighbour ICP after the weighted stage")
      ("no-stop-rule", po::bool_switch(&c.pcl_stopping_only),
       "stop on PCL's convergence criteria only (by default a stage also stops when its correspondences repeat "
       "the previous iteration's: same pose to float rounding, fewer iterations; docs/performance.md)")
      ("global", po::bool_switch(&c.global), "find the start from geometry alone, any yaw and translation, partial "
                                              "overlap allowed (docs/global_alignment.md); implies --refine")
      ("up-axis", po::value(&c.up_axis_text)->default_value(c.up_axis_text),
       "with --global, the axis the search rotates about: auto (both maps' cameras level about z within 8 deg: z, "
       "with tilts up to 16 deg; otherwise each map levelled by its own cameras, as maps written in a first camera's frame need, "
       "a map whose cameras face about one way also by its estimate turned up to 45 deg about their rows), z, or "
       "\"X Y Z\" for both maps (no search tilts, only the final pass's within 4 deg: the fastest, for maps known "
       "to share it)")
      ("threads", tools::rangedValue(&c.settings.threads, 0u, 1024u)->default_value(c.settings.threads),
       "search threads, 0 = all (at most 1024)")
      ("json", po::bool_switch(&c.json), "print the result as one JSON object on the last line of stdout")
      ("plot", po::value(&c.plot_path), "also draw the clouds before and after, top view, target coloured by weight, "
                                        "into this PNG (needs matplotlib; a warning without it)");
  // clang-format on
  po::variables_map vm;
  if (!tools::parseCommandLine(argc, argv, options, vm)) return false;
  interpretCommand(vm, c);
  return true;
}

/// @brief The parsed words turned into settings; a bad value is a command-line error (exit 2), as a bad number
/// is, not a failure of the run.
void interpretCommand(const po::variables_map& vm, AlignCommand& c) {
  tools::requireOutputFolderOf(c.plot_path, "--plot");
  c.settings.stop_on_repeated_correspondences = !c.pcl_stopping_only;
  try {
    c.strategy = parseWeightStrategy(c.strategy_name);
  } catch (const std::invalid_argument& e) {
    throw po::error(std::string("--strategy: ") + e.what());
  }
  try {
    if (!c.displacement_text.empty()) c.displacement = Displacement::parse(c.displacement_text);
  } catch (const std::invalid_argument& e) {
    throw po::error(std::string("--displace: ") + e.what());
  }
  c.settings.k = neighboursFor(c.strategy, c.settings.k);
  if (c.global) c.settings.refine = true;
  if (!vm["up-axis"].defaulted() && !c.global) throw po::error("--up-axis applies only with --global");
  try {
    c.up_axis = tools::parseUpAxisOption(c.up_axis_text);
  } catch (const std::invalid_argument& e) {
    throw po::error(std::string("--up-axis: ") + e.what());
  }
}

/// @brief Reads one map, keeping landmarks with enough observations; refuses a map left empty.
LandmarkMap readMap(const std::string& path, std::size_t min_observations) {
  LandmarkMap map = io::readLandmarkMap(path).withMinObservations(min_observations);
  if (map.landmarks.empty())
    throw std::runtime_error(path + ": no landmark with at least " + std::to_string(min_observations) +
                             " observations");
  return map;
}

/// @brief Reads both maps and moves the source by --displace.
AlignInputs readInputs(const AlignCommand& c) {
  AlignInputs in{readMap(c.source_path, c.min_observations), readMap(c.target_path, c.min_observations)};
  in.source.transform(c.displacement.toIsometry());
  return in;
}

/// @brief What the global search reports beside the alignment: the up axes of the search kept, and whether it ran
/// the other way (the target onto a source much larger than it).
struct GlobalSearchFacts {
  SharedUpAxes up_axes;
  bool reversed = false;
};

/// @brief Runs the weighted ICP, after the global search when --global asks for it (about the up axes
/// --up-axis resolves to; what the search kept returned in `facts`).
AlignmentResult runAlignment(const AlignCommand& c, const AlignInputs& in, const WeightFunction& weight,
                             GlobalSearchFacts& facts) {
  if (!c.global) {
    LandmarkAligner aligner(c.settings);
    aligner.setTarget(toLandmarkCloud(in.target, weight));
    return aligner.align(toLandmarkCloud(in.source, weight));
  }
  const tools::ResolvedUpAxes resolved = tools::resolveUpAxes(c.up_axis, in.source, in.target);
  std::cout << "global search: " << resolved.description << '\n';
  GlobalAlignmentSettings global;
  global.threads = c.settings.threads;
  GlobalLandmarkAligner aligner(global, c.settings);
  aligner.setTarget(toLandmarkCloud(in.target, weight));
  const GlobalLandmarkAlignmentResult both = aligner.align(toLandmarkCloud(in.source, weight), resolved.axes);
  facts.up_axes.source = both.source_up_axis, facts.up_axes.target = both.target_up_axis;
  facts.reversed = both.global.reversed;
  std::cout << "global search: " << both.global.hypotheses_refined << " hypotheses refined, inlier fraction "
            << both.global.inlier_fraction << ", distance limit " << both.global.distance_limit
            << " m, up axes kept: source " << tools::vectorText(facts.up_axes.source) << ", target "
            << tools::vectorText(facts.up_axes.target) << '\n';
  if (both.first_looks > 0)
    std::cout << "global search: " << both.first_looks << " pitched levellings looked at first, "
              << both.alternatives_searched << " of them promising enough to search fully\n";
  if (facts.reversed)
    std::cout << "global search: the source is much larger than the target: the search and the weighted "
                 "ICP ran the other way, the target onto the source (the fitness score and correspondences below are "
                 "the target's landmarks'), the transformation inverted\n";
  return both.alignment;
}

/// @brief Converged by its criteria, not only stopped at the iteration limit (which PCL counts as converged).
bool settled(const AlignmentResult& result) { return result.converged && !result.stopped_at_iteration_limit; }

/// @brief The human-readable summary on stdout.
void printSummary(const AlignCommand& c, const AlignInputs& in, const AlignmentResult& result) {
  std::cout << "source " << in.source.landmarks.size() << " landmarks, target " << in.target.landmarks.size()
            << " landmarks, strategy " << toString(c.strategy) << ", k " << c.settings.k << '\n'
            << (result.degenerate ? "degenerate: " + result.reason + "; not aligned\n" : std::string()) << "converged "
            << (settled(result) ? "yes" : "no") << " after " << result.iterations << " iterations";
  if (c.settings.refine) std::cout << " + " << result.refine_iterations << " refinement";
  if (result.stopped_at_iteration_limit) std::cout << " (stopped at the iteration limit before its criteria were met)";
  std::cout << ", fitness score " << result.fitness_score << ", " << result.correspondences << " correspondences, "
            << std::fixed << std::setprecision(1) << result.time_ms << " ms\n"
            << std::defaultfloat << "transformation (source -> target):\n"
            << result.transformation << '\n';
}

/// @brief The JSON contract (see the top of this file): one object on the last line of stdout.
void printJson(const AlignCommand& c, const AlignInputs& in, const AlignmentResult& result,
               const GlobalSearchFacts& facts) {
  tools::JsonObject json;
  json.add("transformation", Eigen::MatrixXd(result.transformation))
      .add("fitness_score", result.fitness_score)
      .add("iterations", result.iterations)
      .add("refine_iterations", result.refine_iterations)
      .add("converged", result.converged)
      .add("degenerate", result.degenerate);
  if (result.degenerate) json.add("reason", result.reason);
  json.add("stopped_at_iteration_limit", result.stopped_at_iteration_limit)
      .add("correspondences", result.correspondences)
      .add("time_ms", result.time_ms)
      .add("strategy", toString(c.strategy))
      .add("k", static_cast<std::size_t>(c.settings.k))
      .add("source_landmarks", in.source.landmarks.size())
      .add("target_landmarks", in.target.landmarks.size());
  if (c.global)
    json.add("up_axis_source", facts.up_axes.source)
        .add("up_axis_target", facts.up_axes.target)
        .add("reversed", facts.reversed);
  std::cout << json.str() << std::endl;
}

}  // namespace

int main(int argc, char** argv) {
  return tools::runTool("wicp_align", [&] {
    AlignCommand command;
    if (!parseCommand(argc, argv, command)) return 0;
    const AlignInputs inputs = readInputs(command);
    const WeightFunction weight = weightFunction(command.strategy);
    GlobalSearchFacts facts;
    const AlignmentResult result = runAlignment(command, inputs, weight, facts);
    printSummary(command, inputs, result);
    if (command.json) printJson(command, inputs, result, facts);
    if (!command.plot_path.empty())
      tools::plotAlignment("wicp_align", inputs.source, inputs.target, weight, result.transformation, command.plot_path,
                           command.source_path + " onto " + command.target_path + " (" + toString(command.strategy) +
                               ", k " + std::to_string(command.settings.k) + ")");
    if (result.degenerate) return 4;
    return settled(result) ? 0 : 3;
  });
}
