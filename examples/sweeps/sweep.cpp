#include "sweep.h"

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <system_error>
#include <tuple>
#include <utility>

#include <boost/program_options.hpp>

#include "interrupt.h"
#include "plotting.h"
#include "tool_support.h"
#include "weighted_icp/io/map_format.h"
#include "weighted_icp/registration/landmark_point.h"

namespace weighted_icp::sweep {

namespace po = boost::program_options;
namespace fs = std::filesystem;

// ---------------------------------------------------------------------------
// The sweeps

namespace {
Displacement yawOnly(double yaw_deg) {
  Displacement d;
  d.yaw_deg = yaw_deg;
  return d;
}

std::vector<Displacement> quadrants(double a, double b, double yaw_deg) {
  std::vector<Displacement> out;
  for (const double sx : {1.0, -1.0})
    for (const double sy : {1.0, -1.0}) {
      Displacement d;
      d.x = sx * a;
      d.y = sy * b;
      d.yaw_deg = yaw_deg;
      out.push_back(d);
    }
  return out;
}

std::vector<SweepCase> withK(unsigned int k, const std::vector<Displacement>& displacements) {
  std::vector<SweepCase> cases;
  for (const Displacement& d : displacements) cases.push_back({k, d});
  return cases;
}
}  // namespace

std::vector<Displacement> kSweepDisplacements() {
  Displacement paper;  // config.yaml of the paper's experiment code
  paper.y = 1.0;
  paper.z = 0.4;
  paper.roll_deg = 10.0;
  paper.yaw_deg = 22.5;
  return {paper, yawOnly(10), yawOnly(-10), yawOnly(30), yawOnly(-30)};
}

SweepDefinition kSweep() {
  SweepDefinition sweep{"k",
                        "Sweeps the neighbourhood size k over {1,3,5,7,10,15,20} at five displacements.",
                        true,
                        [](unsigned int) {
                          std::vector<SweepCase> cases;
                          for (const unsigned int k : kSweepValues)
                            for (const SweepCase& c : withK(k, kSweepDisplacements())) cases.push_back(c);
                          return cases;
                        },
                        {},
                        {}};
  // Table 1: "the transformation between the two point clouds is fixed while varying k": config.yaml's.
  sweep.paper_cases = [](unsigned int) {
    std::vector<SweepCase> cases;
    for (const unsigned int k : kSweepValues) cases.push_back({k, kSweepDisplacements().front()});
    return cases;
  };
  return sweep;
}

SweepDefinition yawSweep() {
  SweepDefinition sweep{"yaw",
                        "Sweeps the yaw (about z) from 0 to 70 deg in steps of 10, in both directions.",
                        false,
                        [](unsigned int k) {
                          std::vector<Displacement> displacements;
                          for (const double yaw : yawSweepYaws) {
                            displacements.push_back(yawOnly(yaw));
                            if (yaw != 0.0) displacements.push_back(yawOnly(-yaw));
                          }
                          return withK(k, displacements);
                        },
                        {},
                        {}};
  // Section 4.2: "starts at 0 degrees, and is incremented by 10 until 70": one direction.
  sweep.paper_cases = [](unsigned int k) {
    std::vector<Displacement> displacements;
    for (const double yaw : yawSweepYaws) displacements.push_back(yawOnly(yaw));
    return withK(k, displacements);
  };
  return sweep;
}

SweepDefinition xySweep() {
  SweepDefinition sweep{"xy",
                        "Sweeps XY offsets: the four quadrants (+-a, +-a) for a in {0.25,0.5,1,1.5,2} m.",
                        false,
                        [](unsigned int k) {
                          std::vector<SweepCase> cases;
                          for (const double a : xySweepMagnitudes)
                            for (const SweepCase& c : withK(k, quadrants(a, a, 0.0))) cases.push_back(c);
                          return cases;
                        },
                        {},
                        {}};
  // Section 4.3: "by the values 0.25m and 0.5m, and then increased until at least one ICP strategy
  // stopped aligning successfully"; the paper does not give the step: ours is kPaperXyStep.
  sweep.paper_cases = [](unsigned int k) {
    std::vector<SweepCase> cases;
    for (const double a : {0.25, 0.5})
      for (const SweepCase& c : withK(k, quadrants(a, a, 0.0))) cases.push_back(c);
    return cases;
  };
  sweep.paper_extension = [](unsigned int k, int step) {
    const double a = 0.5 + kPaperXyStep * step;
    return withK(k, quadrants(a, a, 0.0));
  };
  return sweep;
}

SweepDefinition xyYawSweep() {
  SweepDefinition sweep{"xy_yaw",
                        "Sweeps XY plus yaw: the quadrants (+-0.5 m, +-0.5 m) at yaw -30, -10, 10, 30 deg.",
                        false,
                        [](unsigned int k) {
                          std::vector<SweepCase> cases;
                          for (const double yaw : xyYawSweepYaws)
                            for (const SweepCase& c : withK(k, quadrants(xyYawSweepOffset, xyYawSweepOffset, yaw)))
                              cases.push_back(c);
                          return cases;
                        },
                        {},
                        {}};
  // Section 4.4: 0.5 m in each quadrant, rotated by 10, -10, 30 and -30 degrees: the same grid as ours.
  sweep.paper_cases = sweep.cases;
  return sweep;
}

// ---------------------------------------------------------------------------
// The maps

FrameRange FrameRange::parse(const std::string& text, const std::string& option) {
  const auto fail = [&] {
    return std::invalid_argument(option + " \"" + text + "\": expected FIRST-LAST frame ids, e.g. 0-119");
  };
  const auto dash = text.find('-');
  if (dash == std::string::npos || dash == 0 || dash + 1 == text.size()) throw fail();
  const auto frame_id = [&](const std::string& part) {
    if (part.find_first_not_of("0123456789") != std::string::npos) throw fail();
    try {
      return static_cast<FrameId>(std::stoull(part));
    } catch (const std::out_of_range&) {
      throw fail();
    }
  };
  const FrameRange range{frame_id(text.substr(0, dash)), frame_id(text.substr(dash + 1))};
  if (range.first > range.last)
    throw std::invalid_argument(option + " \"" + text + "\": the first frame is after the last");
  return range;
}

std::string FrameRange::toString() const { return std::to_string(first) + "-" + std::to_string(last); }

namespace {
LandmarkMap filtered(const LandmarkMap& map, std::size_t min_observations, const std::string& what) {
  LandmarkMap kept = map.withMinObservations(min_observations);
  if (kept.landmarks.empty())
    throw std::runtime_error(what + ": no landmark with at least " + std::to_string(min_observations) +
                             " observations");
  return kept;
}

LandmarkMap cut(const LandmarkMap& session, const FrameRange& range, const std::string& what) {
  LandmarkMap mini = session.miniMap(range.first, range.last);
  if (mini.frames.empty()) throw std::runtime_error(what + ": the map has no frame in this range");
  return mini;
}
}  // namespace

MapPair loadMapPair(const MapSelection& selection) {
  MapPair pair;
  const std::size_t min_observations = selection.min_observations;
  if (!selection.source_path.empty() || !selection.target_path.empty()) {
    if (selection.source_path.empty() || selection.target_path.empty())
      throw std::invalid_argument("give both a source (--source) and a target (--target) map");
    pair.source = filtered(io::readLandmarkMap(selection.source_path), min_observations, selection.source_path);
    pair.target = filtered(io::readLandmarkMap(selection.target_path), min_observations, selection.target_path);
    pair.description = fs::path(selection.source_path).filename().string() + " onto " +
                       fs::path(selection.target_path).filename().string();
    pair.truth_known = fs::equivalent(selection.source_path, selection.target_path);
    return pair;
  }
  if (selection.session_path.empty()) throw std::invalid_argument("no map given");
  const LandmarkMap session = io::readLandmarkMap(selection.session_path);
  const std::string session_name = fs::path(selection.session_path).filename().string();
  pair.truth_known = true;
  if (!selection.frame_ranges) {
    std::tie(pair.target, pair.source) = filtered(session, min_observations, selection.session_path).alternateHalves();
    pair.description = session_name + " odd landmarks onto even landmarks";
    return pair;
  }
  const auto cutFiltered = [&](const FrameRange& range) {
    const std::string what = selection.session_path + " frames " + range.toString();
    return filtered(cut(session, range, what), min_observations, what);
  };
  const auto& [source_frames, target_frames] = *selection.frame_ranges;
  pair.source = cutFiltered(source_frames);
  pair.target = cutFiltered(target_frames);
  pair.description = session_name + " frames " + source_frames.toString() + " onto frames " + target_frames.toString();
  return pair;
}

// ---------------------------------------------------------------------------
// Running

namespace {
struct PlannedRun {
  WeightStrategy strategy;
  unsigned int k;
  Displacement displacement;
};

/// Strategy by strategy (each builds its weighted target once), cases in
/// order, without repeats.
std::vector<PlannedRun> planRuns(const std::vector<SweepCase>& cases) {
  using Key = std::tuple<WeightStrategy, unsigned int, std::array<double, 6>>;
  std::set<Key> planned;
  std::vector<PlannedRun> plan;
  for (const WeightStrategy strategy : allWeightStrategies())
    for (const SweepCase& c : cases) {
      const unsigned int k = neighboursFor(strategy, c.k);
      const Displacement& d = c.displacement;
      if (planned.insert({strategy, k, {d.x, d.y, d.z, d.roll_deg, d.pitch_deg, d.yaw_deg}}).second)
        plan.push_back({strategy, k, d});
    }
  return plan;
}
}  // namespace

std::size_t countRuns(const std::vector<SweepCase>& cases) { return planRuns(cases).size(); }

std::vector<SweepRun> runSweep(const std::vector<SweepCase>& cases, const MapPair& maps,
                               const AlignmentSettings& settings, const std::function<void(const SweepRun&)>& on_run,
                               const std::function<bool()>& stop) {
  if (cases.empty()) throw std::invalid_argument("the sweep has no case");
  std::vector<SweepRun> runs;
  // Per strategy: its weighted target, and one aligner per k so each builds
  // the target's search structures once.
  WeightStrategy strategy = allWeightStrategies().front();
  WeightFunction weight;
  LandmarkCloud::ConstPtr target;
  std::map<unsigned int, LandmarkAligner> aligners;
  for (const PlannedRun& planned : planRuns(cases)) {
    if (stop && stop()) break;
    if (!target || planned.strategy != strategy) {
      strategy = planned.strategy;
      weight = weightFunction(strategy);
      target = toLandmarkCloud(maps.target, weight);
      aligners.clear();
    }
    auto aligner = aligners.find(planned.k);
    if (aligner == aligners.end()) {
      AlignmentSettings with_k = settings;
      with_k.k = planned.k;
      aligner = aligners.emplace(planned.k, LandmarkAligner(with_k)).first;
      aligner->second.setTarget(target);
    }
    const Eigen::Isometry3d motion = planned.displacement.toIsometry();
    LandmarkMap moved = maps.source;
    moved.transform(motion);

    SweepRun run;
    run.strategy = planned.strategy;
    run.k = planned.k;
    run.displacement = planned.displacement;
    run.result = aligner->second.align(toLandmarkCloud(moved, weight));
    if (maps.truth_known) {
      const Eigen::Isometry3d estimate(run.result.transformation);
      const Eigen::Isometry3d truth = motion.inverse();
      run.rotation_error_deg = rotationErrorDeg(estimate, truth);
      run.translation_error_m = translationError(estimate, truth);
    }
    runs.push_back(run);
    if (on_run) on_run(runs.back());
  }
  return runs;
}

// ---------------------------------------------------------------------------
// Output

bool paperSuccess(const SweepRun& run) { return run.result.fitness_score < kPaperSuccessFitness; }

std::optional<bool> truthSuccess(const SweepRun& run) {
  if (!run.rotation_error_deg || !run.translation_error_m) return std::nullopt;
  return *run.rotation_error_deg <= kTruthSuccessRotationDeg && *run.translation_error_m <= kTruthSuccessTranslationM;
}

const std::vector<std::string>& csvColumns() {
  static const std::vector<std::string> columns{"sweep",
                                                "strategy",
                                                "k",
                                                "x",
                                                "y",
                                                "z",
                                                "roll",
                                                "pitch",
                                                "yaw",
                                                "fitness_score",
                                                "iterations",
                                                "refine_iterations",
                                                "converged",
                                                "time_ms",
                                                "rotation_error_deg",
                                                "translation_error_m",
                                                "paper_success",
                                                "truth_success"};
  return columns;
}

namespace {
std::string number(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.10g", value);
  return buffer;
}

std::string optionalNumber(const std::optional<double>& value) { return value ? number(*value) : ""; }
}  // namespace

std::string formatResultsCsv(const std::string& sweep_name, const std::vector<SweepRun>& runs) {
  std::ostringstream csv;
  for (std::size_t i = 0; i < csvColumns().size(); ++i) csv << (i ? "," : "") << csvColumns()[i];
  csv << '\n';
  for (const SweepRun& run : runs) {
    const Displacement& d = run.displacement;
    const AlignmentResult& r = run.result;
    char time_ms[32];
    std::snprintf(time_ms, sizeof(time_ms), "%.3f", r.time_ms);
    csv << sweep_name << ',' << toString(run.strategy) << ',' << run.k << ',' << number(d.x) << ',' << number(d.y)
        << ',' << number(d.z) << ',' << number(d.roll_deg) << ',' << number(d.pitch_deg) << ',' << number(d.yaw_deg)
        << ',' << number(r.fitness_score) << ',' << r.iterations << ',' << r.refine_iterations << ','
        << (r.converged ? 1 : 0) << ',' << time_ms << ',' << optionalNumber(run.rotation_error_deg) << ','
        << optionalNumber(run.translation_error_m) << ',' << (paperSuccess(run) ? 1 : 0) << ',';
    if (const auto truth = truthSuccess(run)) csv << (*truth ? 1 : 0);
    csv << '\n';
  }
  return csv.str();
}

// ---------------------------------------------------------------------------
// The tool

namespace {
constexpr const char* kDefaultSessionMap = "../shared/data/map_fr1_desk.txt";

/// A sweep stopped by SIGINT/SIGTERM between runs: a partial results.csv
/// would read as a finished sweep, so nothing is published (the temporary
/// folder goes with `folder`). Returns the exit code (130/143).
int discardInterrupted(const std::string& tool, io::AtomicFolder& folder, std::size_t done, std::size_t total) {
  folder.discard();
  const int signal = tools::interruptSignal();
  std::cerr << tool << ": interrupted by " << tools::signalName(signal) << " after " << done << " of " << total
            << " runs; no outputs written, " << folder.target().string() << " left as it was\n";
  return tools::interruptExitCode(signal);
}

/// Draws DIR/violin.png from the CSV by the plotting script. The folder is
/// published either way, since its results are complete; returns the exit
/// code: 0, 4 when plotting failed, 130/143 when the plotter was interrupted.
int plotAndPublish(const std::string& tool, io::AtomicFolder& folder) {
  const std::string csv_path = (folder.path() / "results.csv").string();
  const std::string published_csv = (folder.target() / "results.csv").string();
  const std::vector<std::string> plot_command{WEIGHTED_ICP_PYTHON, WEIGHTED_ICP_PLOT_SCRIPT, csv_path};
  try {
    tools::runProcess(plot_command);  // no shell, so paths need no quoting
  } catch (const std::exception& e) {
    std::error_code ignored;
    fs::remove(folder.path() / "violin.png", ignored);  // a plot the plotter may have left half-written
    folder.publish();
    if (const int signal = tools::interruptSignal()) {  // the plotter got the signal too
      std::cerr << tool << ": interrupted by " << tools::signalName(signal) << " while plotting; the results are "
                << "complete in " << published_csv << ", no plot\n";
      return tools::interruptExitCode(signal);
    }
    std::cerr << tool << ": plotting failed: " << e.what() << "\n  the results are complete in " << published_csv
              << "; plot them later with: " << plot_command[0] << ' ' << plot_command[1] << ' ' << published_csv
              << '\n';
    return 4;
  }
  folder.publish();
  std::cout << tool << ": wrote " << (folder.target() / "violin.png").string() << std::endl;
  return 0;
}
}  // namespace

/// The paper's XY rule: further steps of paper_extension until one in which a strategy fails by the
/// paper's rule (its runs included), or kPaperMaxExtensionSteps.
void extendUntilFailure(const SweepDefinition& sweep, unsigned int k, const MapPair& maps,
                        const AlignmentSettings& settings, const std::function<void(const SweepRun&)>& on_run,
                        std::vector<SweepRun>& runs) {
  const auto any_failed = [](const std::vector<SweepRun>& some) {
    return std::any_of(some.begin(), some.end(), [](const SweepRun& run) { return !paperSuccess(run); });
  };
  if (any_failed(runs)) return;
  for (int step = 1; step <= kPaperMaxExtensionSteps && !tools::interrupted(); ++step) {
    const std::vector<SweepRun> more =
        runSweep(sweep.paper_extension(k, step), maps, settings, on_run, tools::interrupted);
    runs.insert(runs.end(), more.begin(), more.end());
    if (any_failed(more)) return;
  }
}

namespace {

/// @brief What a sweep tool's command line asks for.
struct SweepCommand {
  std::string out_dir;
  std::string preset = "ours";
  MapSelection selection;
  unsigned int k = 5;
  AlignmentSettings settings;
  bool overwrite = false;
  bool plot = true;
};

/// @brief The sweep tools' options; the k option only where the sweep does not vary k itself.
po::options_description sweepOptions(const std::string& tool, const SweepDefinition& sweep, SweepCommand& c,
                                     std::string& source_frames, std::string& target_frames) {
  po::options_description options(
      tool + " [--map SESSION.txt | --source A.txt --target B.txt] [options]\n" + sweep.description +
      "\nAligns the source onto the target with base (plain ICP, k = 1), covariance, observations\n"
      "and mean-distance at each case; writes DIR/results.csv, DIR/run.json and DIR/violin.png.\n"
      "Exit status: 0 ok, 1 error, 2 bad command line, 4 results written but plotting failed.\nOptions");
  // One option per line reads as a table: not reflowed.
  // clang-format off
  options.add_options()
      ("help,h", "print this help")
      ("map", po::value(&c.selection.session_path),
       "session map to cut the two mini-maps from (default, when no map is given: "
       "../shared/data/map_fr1_desk.txt relative to the current folder)")
      ("source-frames", po::value(&source_frames),
       "cut the source mini-map from these frames of --map, e.g. 0-119 (with --target-frames); default: "
       "the session's odd landmarks onto its even ones, the same scene with disjoint points")
      ("target-frames", po::value(&target_frames), "cut the target mini-map from these frames, e.g. 120-239")
      ("source", po::value(&c.selection.source_path), "source map file (with --target, instead of --map)")
      ("target", po::value(&c.selection.target_path), "target map file")
      ("min-observations", tools::rangedValue(&c.selection.min_observations, std::size_t{0})
                               ->default_value(c.selection.min_observations),
       "drop landmarks observed fewer times");
  // clang-format on
  if (!sweep.sweeps_k)
    options.add_options()("k", tools::rangedValue(&c.k, 1u, 1000u)->default_value(c.k),
                          "neighbours among which the heaviest is chosen (weighted strategies; 1-1000)");
  // One option per line reads as a table: not reflowed.
  // clang-format off
  options.add_options()
      ("max-iterations", tools::rangedValue(&c.settings.max_iterations, 1, 1000000)->default_value(c.settings.max_iterations),
       "ICP iteration limit (per stage)")
      ("refine", po::bool_switch(&c.settings.refine), "finish each run with nearest-neighbour ICP (k = 1)")
      ("threads", tools::rangedValue(&c.settings.threads, 0u, 1024u)->default_value(c.settings.threads),
       "search threads, 0 = all (at most 1024); results do not depend on it")
      ("out", po::value(&c.out_dir)->default_value(c.out_dir), "output folder (refused if not empty)")
      ("overwrite", po::bool_switch(&c.overwrite),
       "replace --out if it is not empty (nothing of an earlier sweep is left in it)")
      ("no-plot", "write the CSV only")
      ("preset", po::value(&c.preset)->default_value(c.preset),
       "grid: 'ours' (this project's, see docs/experiments.md) or 'paper' (the paper's Section 4 grid and "
       "stopping rule; the XY sweep then grows beyond 0.5 m in steps of 0.25 m until a strategy fails by "
       "fitness >= 0.0037)");
  // clang-format on
  return options;
}

/// @brief Parses and checks a sweep tool's command line; false when only --help was asked for.
bool parseSweepCommand(const std::string& tool, const SweepDefinition& sweep, int argc, const char* const argv[],
                       SweepCommand& c) {
  c.out_dir = "out/sweep_" + sweep.name;
  std::string source_frames, target_frames;
  const po::options_description options = sweepOptions(tool, sweep, c, source_frames, target_frames);
  po::variables_map vm;
  if (!tools::parseCommandLine(argc, argv, options, vm)) return false;

  const bool files = vm.count("source") || vm.count("target");
  if (files && vm.count("map")) throw std::invalid_argument("give either --map or --source/--target, not both");
  if (vm.count("source-frames") != vm.count("target-frames"))
    throw std::invalid_argument("give both --source-frames and --target-frames, or neither");
  if (files && vm.count("source-frames"))
    throw std::invalid_argument("--source-frames/--target-frames cut a --map; they do not apply to --source/--target");
  if (!files && !vm.count("map")) {
    if (!fs::exists(kDefaultSessionMap))
      throw std::runtime_error(std::string("no map given and the default --map ") + kDefaultSessionMap +
                               " does not exist in " + fs::current_path().string() +
                               "; pass --map SESSION.txt or --source A.txt --target B.txt");
    c.selection.session_path = kDefaultSessionMap;
  }
  if (vm.count("source-frames"))
    c.selection.frame_ranges.emplace(FrameRange::parse(source_frames, "--source-frames"),
                                     FrameRange::parse(target_frames, "--target-frames"));
  if (sweep.sweeps_k) c.k = 0;
  c.settings.refine_max_iterations = c.settings.max_iterations;
  c.plot = vm.count("no-plot") == 0;
  return true;
}

/// @brief run.json: what was run, on what, and how long it took.
std::string runInfoJson(const std::string& tool, const SweepDefinition& sweep, const SweepCommand& c,
                        const MapPair& maps, std::size_t runs, double seconds) {
  tools::JsonObject run_info;
  run_info.add("tool", tool)
      .add("sweep", sweep.name)
      .add("preset", c.preset)
      .add("maps", maps.description)
      .add("source_landmarks", maps.source.landmarks.size())
      .add("target_landmarks", maps.target.landmarks.size())
      .add("truth_known", maps.truth_known)
      .add("min_observations", c.selection.min_observations)
      .add("max_iterations", c.settings.max_iterations)
      .add("refine", c.settings.refine)
      .add("runs", runs)
      .add("sweep_time_s", seconds);
  if (!sweep.sweeps_k) run_info.add("k", static_cast<std::size_t>(c.k));
  return run_info.str() + "\n";
}

}  // namespace

int runSweepTool(const std::string& tool, const SweepDefinition& sweep, int argc, const char* const argv[]) {
  tools::installInterruptHandlers();
  return tools::runTool(tool, [&] {
    SweepCommand c;
    if (!parseSweepCommand(tool, sweep, argc, argv, c)) return 0;

    const MapPair maps = loadMapPair(c.selection);
    if (c.preset != "ours" && c.preset != "paper")
      throw po::error("--preset must be ours or paper (got " + c.preset + ")");
    const bool paper = c.preset == "paper";
    const std::vector<SweepCase> cases = paper ? sweep.paper_cases(c.k) : sweep.cases(c.k);
    std::cout << tool << ": " << maps.description << " (" << maps.source.landmarks.size() << " onto "
              << maps.target.landmarks.size() << " landmarks), " << cases.size() << " cases, " << countRuns(cases)
              << " runs" << (c.settings.refine ? ", with refinement" : "") << std::endl;
    // Opened early, so a refused --out fails before the runs; published whole at the end.
    io::AtomicFolder folder = tools::openOutputFolder(c.out_dir, c.overwrite);

    const auto start = std::chrono::steady_clock::now();
    // With the paper's XY rule the run count is an upper bound: the sweep stops at the first failing step.
    std::size_t planned = countRuns(cases);
    if (paper && sweep.paper_extension)
      for (int step = 1; step <= kPaperMaxExtensionSteps; ++step)
        planned += countRuns(sweep.paper_extension(c.k, step));
    tools::Progress progress(tool, planned);
    const auto on_run = [&](const SweepRun& run) {
      progress.step(toString(run.strategy) + " k " + std::to_string(run.k) + " (" + run.displacement.toString() + ")");
    };
    std::vector<SweepRun> runs = runSweep(cases, maps, c.settings, on_run, tools::interrupted);
    if (paper && sweep.paper_extension) extendUntilFailure(sweep, c.k, maps, c.settings, on_run, runs);
    progress.finish();
    if (tools::interrupted()) return discardInterrupted(tool, folder, runs.size(), countRuns(cases));
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

    tools::writeTextFile((folder.path() / "results.csv").string(), formatResultsCsv(sweep.name, runs));
    tools::writeTextFile((folder.path() / "run.json").string(),
                         runInfoJson(tool, sweep, c, maps, runs.size(), seconds));
    const std::string csv_path = (folder.target() / "results.csv").string();
    std::cout << tool << ": " << runs.size() << " runs in " << std::lround(seconds) << " s; wrote " << csv_path
              << std::endl;
    if (c.plot) return plotAndPublish(tool, folder);
    folder.publish();
    return 0;
  });
}

}  // namespace weighted_icp::sweep
