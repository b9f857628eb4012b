#pragma once
// The parameter sweeps of the paper's experiments (neighbourhood size k, yaw,
// XY offsets, XY plus yaw): one implementation, the four wicp_sweep_* tools
// differ only in the cases their SweepDefinition generates.
//
// A sweep moves the source map by each case's displacement, aligns it onto
// the target with every weight strategy and writes one CSV row per run.

#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "weighted_icp/registration/landmark_alignment.h"
#include "weighted_icp/registration/landmark_map.h"
#include "weighted_icp/registration/rigid_motion.h"
#include "weighted_icp/registration/weight_strategies.h"

namespace weighted_icp::sweep {

/// One alignment problem: the source moved by `displacement`, aligned with
/// `k` neighbours (base, plain ICP, always uses k = 1).
struct SweepCase {
  unsigned int k = 5;
  Displacement displacement;
};

struct SweepDefinition {
  /// "k", "yaw", "xy" or "xy_yaw": the CSV's `sweep` column, the default
  /// output folder out/sweep_<name> and the plot's grouping.
  std::string name;
  std::string description;  // for --help
  /// The k sweep takes k from its cases; the others take it from --k.
  bool sweeps_k = false;
  std::function<std::vector<SweepCase>(unsigned int k)> cases;
  /// The paper's grid for this sweep (`--preset paper`), read from its Section 4.
  std::function<std::vector<SweepCase>(unsigned int k)> paper_cases;
  /// Under `--preset paper`: after paper_cases, further cases from this function, one step at a time
  /// (step 1, 2, ...), until a step in which at least one strategy fails by the paper's rule (the XY
  /// sweep: "then increased until at least one ICP strategy stopped aligning successfully"), at most
  /// kPaperMaxExtensionSteps steps. Empty: no extension.
  std::function<std::vector<SweepCase>(unsigned int k, int step)> paper_extension;
};

/// The paper's success rule: PCL's fitness score below 0.0037 (for its map pair, Section 4).
inline constexpr double kPaperSuccessFitness = 0.0037;
/// Ours: the result within 2 degrees and 0.1 m of the truth (needs the truth).
inline constexpr double kTruthSuccessRotationDeg = 2.0;
inline constexpr double kTruthSuccessTranslationM = 0.1;
/// Step of the paper's XY extension beyond 0.5 m, and the most steps taken (0.75 m .. 5.5 m).
inline constexpr double kPaperXyStep = 0.25;
inline constexpr int kPaperMaxExtensionSteps = 20;

/// k in kSweepValues at each of kSweepDisplacements().
SweepDefinition kSweep();
/// Yaw 0..70 deg in steps of 10, each in both directions (0 once).
SweepDefinition yawSweep();
/// The four quadrants (+-a, +-a) for each magnitude a in xySweepMagnitudes.
SweepDefinition xySweep();
/// The quadrants (+-0.5 m, +-0.5 m) at each yaw in xyYawSweepYaws.
SweepDefinition xyYawSweep();

inline const std::vector<unsigned int> kSweepValues{1, 3, 5, 7, 10, 15, 20};
/// The paper's configured displacement (config.yaml) and yaw +-10, +-30 deg,
/// so each k has several samples.
std::vector<Displacement> kSweepDisplacements();
inline const std::vector<double> yawSweepYaws{0, 10, 20, 30, 40, 50, 60, 70};
inline const std::vector<double> xySweepMagnitudes{0.25, 0.5, 1.0, 1.5, 2.0};
inline constexpr double xyYawSweepOffset = 0.5;
inline const std::vector<double> xyYawSweepYaws{-30, -10, 10, 30};

/// Frames [first, last] of a session map.
struct FrameRange {
  FrameId first = 0;
  FrameId last = 0;
  /// Parses "FIRST-LAST"; throws std::invalid_argument naming `option`.
  static FrameRange parse(const std::string& text, const std::string& option);
  std::string toString() const;
};

/// Where the two maps come from: two files, or one session map split into
/// alternate landmarks (LandmarkMap::alternateHalves: disjoint points of the
/// same scene) or cut into two frame ranges (LandmarkMap::miniMap).
struct MapSelection {
  std::string source_path, target_path;  // both set, or both empty
  std::string session_path;              // used when the paths above are empty
  /// Frame ranges (source, target) to cut; none: alternate halves.
  std::optional<std::pair<FrameRange, FrameRange>> frame_ranges;
  std::size_t min_observations = 2;
};

struct MapPair {
  LandmarkMap source, target;  // landmarks with >= min_observations only
  std::string description;     // names the maps, for titles and logs
  /// True when both come from one session map or one file: they then share
  /// a world frame, and the alignment that undoes displacement D is D^-1.
  bool truth_known = false;
};

/// Reads and cuts the maps. Throws naming the file (or frame range) when a
/// file is missing or malformed, a range selects no frame, or a map keeps
/// no landmark after the observation filter.
MapPair loadMapPair(const MapSelection& selection);

struct SweepRun {
  WeightStrategy strategy = WeightStrategy::Base;
  unsigned int k = 1;  // as run: 1 for base
  Displacement displacement;
  AlignmentResult result;
  /// Against the inverse displacement; empty when the truth is unknown.
  std::optional<double> rotation_error_deg, translation_error_m;
};

/// Every strategy on every case. A run is (strategy, k as run, displacement),
/// and none is repeated: in the k sweep base runs once per displacement.
/// `settings.k` is ignored (each case has its k). `on_run` is called after
/// each run, for progress. Results do not depend on settings.threads.
/// `stop`, when given, is asked before each run: true ends the sweep early,
/// returning the runs made so far (a Ctrl-C).
std::vector<SweepRun> runSweep(const std::vector<SweepCase>& cases, const MapPair& maps,
                               const AlignmentSettings& settings,
                               const std::function<void(const SweepRun&)>& on_run = {},
                               const std::function<bool()>& stop = {});
/// How many runs runSweep() makes for `cases`.
std::size_t countRuns(const std::vector<SweepCase>& cases);

/// Whether a run succeeded by the paper's rule (fitness < kPaperSuccessFitness).
bool paperSuccess(const SweepRun& run);
/// Whether it succeeded by ours (errors within kTruthSuccess*); empty when the truth is unknown.
std::optional<bool> truthSuccess(const SweepRun& run);

/// The header row of results.csv.
const std::vector<std::string>& csvColumns();
/// results.csv: the header and one row per run; error cells empty when unknown.
std::string formatResultsCsv(const std::string& sweep_name, const std::vector<SweepRun>& runs);

/// The whole tool: options, maps, runs, DIR/results.csv, DIR/run.json and
/// (unless --no-plot) DIR/violin.png via scripts/plot_sweep.py.
/// Returns the exit status: 0; 1 on errors (printed as "<tool>: error: ...");
/// 2 on command-line errors; 4 when the results were written but the plot
/// could not be made; 130/143 when stopped by SIGINT/SIGTERM (between runs:
/// nothing written; while plotting: the results written, the plot not).
int runSweepTool(const std::string& tool, const SweepDefinition& sweep, int argc, const char* const argv[]);

}  // namespace weighted_icp::sweep
