// wicp_demo: the project's demonstration, runnable with no arguments and no
// data. It generates a synthetic RGB-D SLAM session with exact ground truth,
// cuts the drifting odometry's map into consecutive mini-maps, and aligns each
// mini-map onto the one before it, displaced by a known motion, with every
// weight strategy, with and without refinement. Both mini-maps are in the
// session's frame, so the true alignment is the inverse of the displacement.
//
// Writes to --out: session.txt (the estimated map), session_truth.txt (the
// same landmarks and frames, true), minimaps/minimap_NNN.txt and results.csv
// (one row per alignment), all published together (io::AtomicFolder): --out
// holds one whole run or is left as it was. Mini-maps are written unfiltered: wicp_align
// --source minimaps/minimap_001.txt --target minimaps/minimap_000.txt with the
// same --displace, --strategy and --k reproduces a row.

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <boost/program_options.hpp>

#include "interrupt.h"
#include "tool_support.h"
#include "weighted_icp/core/statistics.h"
#include "weighted_icp/io/map_format.h"
#include "weighted_icp/registration/landmark_alignment.h"
#include "weighted_icp/registration/rigid_motion.h"
#include "weighted_icp/simulation/session.h"

namespace po = boost::program_options;
namespace fs = std::filesystem;
using namespace weighted_icp;

namespace {

struct AlignmentRecord {
  std::size_t target_minimap = 0;  // the source is the next one
  WeightStrategy strategy = WeightStrategy::Base;
  unsigned int k = 1;
  bool refine = false;
  std::size_t source_landmarks = 0;
  std::size_t target_landmarks = 0;
  double rotation_error_deg = 0.0;
  double translation_error_m = 0.0;
  AlignmentResult result;
};

double maximum(const std::vector<double>& values) { return *std::max_element(values.begin(), values.end()); }

std::string minimapFileName(std::size_t index) {
  std::ostringstream name;
  name << "minimap_" << std::setw(3) << std::setfill('0') << index << ".txt";
  return name.str();
}

std::string resultsCsv(const std::vector<AlignmentRecord>& records) {
  std::ostringstream csv;
  csv << std::setprecision(9)
      << "source_minimap,target_minimap,strategy,k,refine,source_landmarks,target_landmarks,rotation_error_deg,"
         "translation_error_cm,fitness_score,iterations,refine_iterations,converged,correspondences,time_ms\n";
  for (const auto& r : records)
    csv << r.target_minimap + 1 << ',' << r.target_minimap << ',' << toString(r.strategy) << ',' << r.k << ','
        << (r.refine ? 1 : 0) << ',' << r.source_landmarks << ',' << r.target_landmarks << ',' << r.rotation_error_deg
        << ',' << r.translation_error_m * 100.0 << ',' << r.result.fitness_score << ',' << r.result.iterations << ','
        << r.result.refine_iterations << ',' << (r.result.converged ? 1 : 0) << ',' << r.result.correspondences << ','
        << r.result.time_ms << '\n';
  return csv.str();
}

/// One row per strategy and refinement: medians and maxima over the pairs.
void printSummaryTable(const std::vector<AlignmentRecord>& records, std::size_t pairs) {
  std::cout << '\n'
            << std::left << std::setw(15) << "strategy" << std::right << std::setw(3) << "k" << std::setw(8) << "refine"
            << std::setw(11) << "rot med" << std::setw(10) << "rot max" << std::setw(11) << "trans med" << std::setw(11)
            << "trans max" << std::setw(13) << "fitness med" << std::setw(10) << "iter med" << std::setw(11)
            << "time med" << std::setw(11) << "converged" << '\n'
            << std::left << std::setw(26) << "" << std::right << std::setw(11) << "[deg]" << std::setw(10) << "[deg]"
            << std::setw(11) << "[cm]" << std::setw(11) << "[cm]" << std::setw(13) << "[m^2]" << std::setw(10) << ""
            << std::setw(11) << "[ms]" << '\n';
  for (const WeightStrategy strategy : allWeightStrategies()) {
    for (const bool refine : {false, true}) {
      std::vector<double> rotation, translation, fitness, iterations, time;
      std::size_t converged = 0;
      unsigned int k = 0;
      for (const auto& r : records) {
        if (r.strategy != strategy || r.refine != refine) continue;
        rotation.push_back(r.rotation_error_deg);
        translation.push_back(r.translation_error_m * 100.0);
        fitness.push_back(r.result.fitness_score);
        iterations.push_back(r.result.iterations + r.result.refine_iterations);
        time.push_back(r.result.time_ms);
        converged += r.result.converged ? 1 : 0;
        k = r.k;
      }
      std::ostringstream converged_text;
      converged_text << converged << '/' << pairs;
      std::cout << std::left << std::setw(15) << toString(strategy) << std::right << std::setw(3) << k << std::setw(8)
                << (refine ? "yes" : "no") << std::fixed << std::setprecision(3) << std::setw(11) << median(rotation)
                << std::setw(10) << maximum(rotation) << std::setprecision(2) << std::setw(11) << median(translation)
                << std::setw(11) << maximum(translation) << std::scientific << std::setprecision(2) << std::setw(13)
                << median(fitness) << std::fixed << std::setprecision(1) << std::setw(10) << median(iterations)
                << std::setw(11) << median(time) << std::setw(11) << converged_text.str() << std::defaultfloat << '\n';
    }
  }
  std::cout << "errors against the true alignment; iterations of both stages; time of the alignment alone\n";
}

/// @brief What the command line asks for.
struct DemoCommand {
  simulation::SyntheticSessionOptions session_options;
  // One search thread by default: mini-maps of ~1000 landmarks leave threads
  // little to share, and on a busy machine a thread waiting to be scheduled
  // stalls every ICP iteration (measured: 8x slower with 2 threads under load).
  std::size_t frames_per_minimap = 40, min_observation_count = 2;
  unsigned int neighbours = 5, thread_count = 1;
  std::string displacement_text = "0.2 -0.15 0.05 3 -2 15", out_dir = "out/demo";
  bool overwrite = false;
};

/// @brief Parses and checks the command line; false when only --help was asked for.
bool parseCommand(int argc, char** argv, DemoCommand& c) {
  simulation::SyntheticSessionOptions& session = c.session_options;
  po::options_description options(
      "wicp_demo [options]\n"
      "Aligns consecutive mini-maps of a synthetic RGB-D SLAM session with exact ground truth,\n"
      "with every weight strategy, and reports the errors. Options");
  // One option per line reads as a table: not reflowed.
  // clang-format off
  options.add_options()
      ("help,h", "print this help")
      ("seed", tools::rangedValue(&session.seed, std::uint64_t{0})->default_value(session.seed),
       "session random seed (>= 0)")
      ("frames", tools::rangedValue(&session.num_frames, std::size_t{2}, std::size_t{100000})
                     ->default_value(session.num_frames),
       "camera frames of the session (2-100000)")
      ("landmarks", tools::rangedValue(&session.num_landmarks, std::size_t{1}, std::size_t{10000000})
                        ->default_value(session.num_landmarks),
       "landmarks placed in the room (only observed ones are kept)")
      ("frames-per-minimap", tools::rangedValue(&c.frames_per_minimap, std::size_t{1})->default_value(c.frames_per_minimap),
       "consecutive frames per mini-map (fewer than --frames)")
      ("displace", po::value(&c.displacement_text)->default_value(c.displacement_text),
       "motion applied to each source mini-map: \"x y z roll pitch yaw\" (metres, degrees; "
       "R = Rz(yaw) Ry(pitch) Rx(roll))")
      ("k", tools::rangedValue(&c.neighbours, 1u, 1000u)->default_value(c.neighbours),
       "neighbours among which the heaviest is chosen (1-1000; base uses 1)")
      ("min-observations", tools::rangedValue(&c.min_observation_count, std::size_t{1}, std::size_t{1000000})
                               ->default_value(c.min_observation_count),
       "align only landmarks observed this often within the mini-map (the paper uses 2)")
      ("threads", tools::rangedValue(&c.thread_count, 0u, 1024u)->default_value(c.thread_count),
       "search threads, 0 = all (at most 1024)")
      ("out", po::value(&c.out_dir)->default_value(c.out_dir), "output folder (refused if not empty)")
      ("overwrite", po::bool_switch(&c.overwrite),
       "replace --out if it is not empty (nothing of an earlier run is left in it)");
  // clang-format on
  po::variables_map vm;
  if (!tools::parseCommandLine(argc, argv, options, vm)) return false;
  // The one bound that depends on another option.
  if (c.frames_per_minimap >= session.num_frames)
    tools::throwOutOfRange("frames-per-minimap", std::to_string(c.frames_per_minimap), 1,
                           static_cast<long long>(session.num_frames) - 1);
  if (c.out_dir.empty()) throw std::invalid_argument("--out must name a folder");
  return true;
}

/// @brief Generates the session and says what it is: size, generation time, the odometry's final drift.
simulation::SyntheticSession generateSession(const simulation::SyntheticSessionOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  simulation::SyntheticSession session = simulation::generateSyntheticSession(options);
  const double generation_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::size_t observations = 0;
  for (const auto& landmark : session.estimated.landmarks) observations += landmark.observations.size();
  const FrameId last_frame = session.estimated.frames.rbegin()->first;
  const Eigen::Isometry3d& last_estimated = session.estimated.frames.at(last_frame);
  const Eigen::Isometry3d& last_true = session.truth.frames.at(last_frame);
  std::cout << "session (seed " << options.seed << "): " << session.estimated.frames.size() << " frames, "
            << session.estimated.landmarks.size() << " landmarks observed of " << options.num_landmarks << " placed, "
            << observations << " observations; generated in " << std::fixed << std::setprecision(0)
            << generation_s * 1000.0 << " ms\n"
            << "odometry drift at the last frame: " << std::setprecision(1)
            << translationError(last_estimated, last_true) * 100.0 << " cm, " << std::setprecision(2)
            << rotationErrorDeg(last_estimated, last_true) << " deg\n"
            << std::defaultfloat;
  return session;
}

/// @brief The mini-maps as aligned: landmarks with enough observations; refuses a mini-map left empty.
std::vector<LandmarkMap> filterMiniMaps(const std::vector<LandmarkMap>& minimaps, std::size_t min_observations) {
  std::vector<LandmarkMap> filtered;
  for (std::size_t i = 0; i < minimaps.size(); ++i) {
    filtered.push_back(minimaps[i].withMinObservations(min_observations));
    if (filtered.back().landmarks.empty())
      throw std::runtime_error("mini-map " + std::to_string(i) + " has no landmark with at least " +
                               std::to_string(min_observations) +
                               " observations (lower --min-observations or raise --frames-per-minimap)");
  }
  return filtered;
}

/// @brief Aligns one displaced source onto its target with one strategy, with refinement or not.
AlignmentRecord alignOnce(const DemoCommand& c, std::size_t pair, const LandmarkMap& source, const LandmarkMap& target,
                          WeightStrategy strategy, bool refine, const Eigen::Isometry3d& true_alignment) {
  const WeightFunction weight = weightFunction(strategy);
  AlignmentSettings settings;
  settings.k = neighboursFor(strategy, c.neighbours);
  settings.refine = refine;
  settings.threads = c.thread_count;
  LandmarkAligner aligner(settings);
  aligner.setTarget(toLandmarkCloud(target, weight));
  AlignmentRecord record;
  record.target_minimap = pair;
  record.strategy = strategy;
  record.k = settings.k;
  record.refine = refine;
  record.source_landmarks = source.landmarks.size();
  record.target_landmarks = target.landmarks.size();
  record.result = aligner.align(toLandmarkCloud(source, weight));
  const Eigen::Isometry3d estimate(record.result.transformation);
  record.rotation_error_deg = rotationErrorDeg(estimate, true_alignment);
  record.translation_error_m = translationError(estimate, true_alignment);
  return record;
}

/// @brief Every consecutive pair with every strategy, with and without refinement; stops early on Ctrl-C.
std::vector<AlignmentRecord> alignAllPairs(const DemoCommand& c, const std::vector<LandmarkMap>& minimaps,
                                           const Displacement& displacement) {
  const Eigen::Isometry3d true_alignment = displacement.toIsometry().inverse();
  const std::size_t pairs = minimaps.size() - 1;
  const std::vector<WeightStrategy>& strategies = allWeightStrategies();
  tools::Progress progress("aligning", pairs * strategies.size() * 2);
  std::vector<AlignmentRecord> records;
  for (std::size_t pair = 0; pair < pairs && !tools::interrupted(); ++pair) {
    LandmarkMap source = minimaps[pair + 1];
    source.transform(displacement.toIsometry());
    for (const WeightStrategy strategy : strategies) {
      for (const bool refine : {false, true}) {
        if (tools::interrupted()) break;
        records.push_back(alignOnce(c, pair, source, minimaps[pair], strategy, refine, true_alignment));
        progress.step("pair " + std::to_string(pair) + " " + toString(strategy) + (refine ? " +refine" : ""));
      }
    }
  }
  progress.finish();
  return records;
}

/// @brief Writes the run into the temporary folder and publishes it in one rename.
void writeOutputs(io::AtomicFolder& folder, const simulation::SyntheticSession& session,
                  const std::vector<LandmarkMap>& minimaps, const std::vector<AlignmentRecord>& records) {
  const fs::path out = folder.path();
  fs::create_directories(out / "minimaps");
  io::writeLandmarkMap(session.estimated, (out / "session.txt").string());
  io::writeLandmarkMap(session.truth, (out / "session_truth.txt").string());
  for (std::size_t i = 0; i < minimaps.size(); ++i)
    io::writeLandmarkMap(minimaps[i], (out / "minimaps" / minimapFileName(i)).string());
  tools::writeTextFile((out / "results.csv").string(), resultsCsv(records));
  folder.publish();
}

}  // namespace

int main(int argc, char** argv) {
  tools::installInterruptHandlers();  // Ctrl-C stops between alignments, writing nothing
  return tools::runTool("wicp_demo", [&] {
    const auto start = std::chrono::steady_clock::now();
    DemoCommand command;
    if (!parseCommand(argc, argv, command)) return 0;
    const Displacement displacement = Displacement::parse(command.displacement_text);
    // Opened before the long run, so a refused --out costs nothing.
    io::AtomicFolder folder = tools::openOutputFolder(command.out_dir, command.overwrite);

    const simulation::SyntheticSession session = generateSession(command.session_options);
    const std::vector<LandmarkMap> minimaps = session.estimated.splitIntoMiniMaps(command.frames_per_minimap);
    const std::vector<LandmarkMap> aligned_minimaps = filterMiniMaps(minimaps, command.min_observation_count);
    std::cout << minimaps.size() << " mini-maps of " << command.frames_per_minimap
              << " frames (landmarks with >= " << command.min_observation_count << " observations:";
    for (const auto& minimap : aligned_minimaps) std::cout << ' ' << minimap.landmarks.size();
    std::cout << ")\naligning mini-map i+1 onto mini-map i, source displaced by " << displacement.toString()
              << "; truth: its inverse\n";

    const std::size_t pairs = minimaps.size() - 1;
    const std::vector<AlignmentRecord> records = alignAllPairs(command, aligned_minimaps, displacement);
    if (const int signal = tools::interruptSignal()) {
      std::cerr << "wicp_demo: interrupted by " << tools::signalName(signal) << " after " << records.size() << " of "
                << pairs * allWeightStrategies().size() * 2 << " alignments; no outputs written, " << command.out_dir
                << " left as it was\n";
      return tools::interruptExitCode(signal);
    }
    writeOutputs(folder, session, minimaps, records);
    printSummaryTable(records, pairs);
    const double total_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::cout << "\nwrote " << (folder.target() / "session.txt").string() << ", session_truth.txt, " << minimaps.size()
              << " mini-maps in minimaps/, results.csv\n"
              << "total " << std::fixed << std::setprecision(1) << total_s << " s\n";
    return 0;
  });
}
