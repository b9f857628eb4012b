// wicp_global_sweep: measures alignment from any start on partial-overlap
// pairs cut from one map (real or synthetic) with exact truth, over a grid of
// yaw and XY displacements: success rate, errors and time per alignment.
//
// Pairs: for each overlap fraction o, mini-maps A = frames [0, L) and
// B = frames [F - L, F) of the F-frame map, L = F / (2 - o), so a fraction o
// of each one's frames is shared; with --disjoint the landmarks both saw are
// dealt out by id parity, so no landmark is in both. --halves adds the
// alternate-landmark halves of the whole map. B is displaced and aligned onto A.
// --inside F-L,... pairs instead each mini-map of frames F-L (B) with the whole
// map (A), the mini-map's landmarks dealt out by id parity with --disjoint;
// --swap displaces and aligns A onto B instead (the whole map onto a mini-map).
//
// Displacements are rotations about the world's z axis and translations in its
// xy plane. The world is the map's own frame unless --camera-frame (the map
// re-expressed in its first camera's frame, as a SLAM without gravity writes
// it), --map-pose (the map's frame placed in a z-up world, e.g. by ground
// truth; after --camera-frame, the camera frame's) or --tilt (the map
// re-expressed in a frame turned about x) says otherwise: then the search's
// --up-axis matters.

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

#include <boost/program_options.hpp>

#include <pcl/common/io.h>
#include <pcl/features/fpfh.h>
#include <pcl/features/normal_3d.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/registration/sample_consensus_prerejective.h>

#include "frame_ranges.h"
#include "tool_support.h"
#include "up_axis_option.h"
#include "weighted_icp/core/statistics.h"
#include "weighted_icp/io/map_format.h"
#include "weighted_icp/registration/global_landmark_alignment.h"
#include "weighted_icp/registration/rigid_motion.h"
#include "weighted_icp/simulation/session.h"

namespace po = boost::program_options;
using namespace weighted_icp;

namespace {

struct Pair {
  std::string name;
  LandmarkMap source, target;
};

/// @brief Reads one finite number of a list option; a command-line error (exit 2) naming the option otherwise.
double parseNumber(const std::string& item, const std::string& option) {
  std::size_t used = 0;
  double value = 0.0;
  try {
    value = std::stod(item, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != item.size() || !std::isfinite(value))
    throw po::error("--" + option + ": '" + item + "' is not a finite number");
  return value;
}

/// @brief A comma-separated list of numbers, e.g. --yaws 0,30,60.
std::vector<double> parseList(const std::string& text, const std::string& option) {
  std::vector<double> values;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) values.push_back(parseNumber(item, option));
  if (values.empty()) throw po::error("--" + option + " must list at least one number");
  return values;
}

/// @brief A comma-separated list of x:y pairs, e.g. --xy 0:0,2:-1.
std::vector<std::pair<double, double>> parseXyList(const std::string& text) {
  std::vector<std::pair<double, double>> xys;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    const auto colon = item.find(':');
    if (colon == std::string::npos) throw po::error("--xy: '" + item + "' is not x:y");
    xys.emplace_back(parseNumber(item.substr(0, colon), "xy"), parseNumber(item.substr(colon + 1), "xy"));
  }
  if (xys.empty()) throw po::error("--xy must list at least one x:y");
  return xys;
}

/// Each mini-map of `ranges` (the source) paired with the whole map (the target); with `disjoint` the landmarks both
/// hold dealt out by id parity (the mini-map keeps the even ones).
std::vector<Pair> makeInsidePairs(const LandmarkMap& map, const std::vector<tools::FrameRange>& ranges, bool disjoint,
                                  std::size_t min_observations) {
  std::vector<Pair> pairs;
  for (const auto& range : ranges) {
    LandmarkMap mini = map.miniMap(range.first, range.last), whole = map;
    if (disjoint) dealOutSharedLandmarks(mini, whole);
    std::ostringstream name;
    name << "frames [" << range.first << "-" << range.last << "] in the whole map" << (disjoint ? " disjoint" : "");
    pairs.push_back(
        {name.str(), mini.withMinObservations(min_observations), whole.withMinObservations(min_observations)});
  }
  return pairs;
}

/// The overlap pairs (or, given `inside`, the mini-maps of those frames each with the whole map), the halves when
/// asked for.
std::vector<Pair> makePairs(const LandmarkMap& map, const std::vector<double>& overlaps,
                            const std::vector<tools::FrameRange>& inside, bool disjoint, bool halves,
                            std::size_t min_observations) {
  std::vector<Pair> pairs = makeInsidePairs(map, inside, disjoint, min_observations);
  const FrameId first = map.frames.begin()->first, last = map.frames.rbegin()->first;
  const double frames = static_cast<double>(last - first + 1);
  for (double o : overlaps) {
    if (!inside.empty()) break;  // --inside pairs instead
    const auto length = static_cast<FrameId>(std::llround(frames / (2.0 - o)));
    LandmarkMap a = map.miniMap(first, first + length - 1), b = map.miniMap(last - length + 1, last);
    if (disjoint) dealOutSharedLandmarks(a, b);
    std::ostringstream name;
    name << "overlap " << o << (disjoint ? " disjoint" : "") << " [" << first << "-" << first + length - 1 << "] ["
         << last - length + 1 << "-" << last << "]";
    pairs.push_back({name.str(), b.withMinObservations(min_observations), a.withMinObservations(min_observations)});
  }
  if (halves) {
    auto [even, odd] = map.withMinObservations(min_observations).alternateHalves();
    pairs.push_back({"alternate halves", odd, even});
  }
  return pairs;
}

/// @brief "tx ty tz qx qy qz qw" as a pose; a command-line error naming --map-pose otherwise.
Eigen::Isometry3d parseTumPose(const std::string& text) {
  std::istringstream in(text);
  double v[7];
  std::string rest;
  for (double& x : v)
    if (!(in >> x) || !std::isfinite(x))
      throw po::error("--map-pose: expected \"tx ty tz qx qy qz qw\", got '" + text + "'");
  if (in >> rest) throw po::error("--map-pose: expected 7 numbers, got more in '" + text + "'");
  const Eigen::Quaterniond q(v[6], v[3], v[4], v[5]);
  if (std::abs(q.norm() - 1.0) > 1e-3) throw po::error("--map-pose: the quaternion is not a unit one");
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = q.normalized().toRotationMatrix();
  pose.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
  return pose;
}

/// @brief What the command line asks for.
struct GlobalSweepCommand {
  std::string map_path, method = "global", perturb_text, map_pose_text, up_axis_text = "auto";
  bool camera_frame = false;
  double tilt_deg = 0.0;  // --tilt: the map re-expressed in a frame this far off z
  tools::UpAxisOption up_axis;
  /// The map's frame in the z-up world displacements are made in (--camera-frame, --map-pose).
  Eigen::Isometry3d world_from_map = Eigen::Isometry3d::Identity();
  double fpfh_radius_scale = 1.0;
  bool synthetic = false, disjoint = false, halves = false, swap = false, verbose = false;
  std::vector<tools::FrameRange> inside;  // --inside: mini-maps of these frames, each with the whole map
  std::uint64_t seed = 1;
  std::size_t landmarks = 8000, min_observations = 2;
  std::vector<double> overlaps, yaws;
  std::vector<std::pair<double, double>> xys;
  GlobalAlignmentSettings settings;
};

/// @brief Success means within these of the truth (the 2 degrees and 5 cm).
constexpr double kMaxRotationDeg = 2.0, kMaxTranslationM = 0.05;

/// @brief The global search's settings the sweep can change, as a table of options writing into `g`.
po::options_description searchOptions(GlobalAlignmentSettings& g) {
  po::options_description options("The global search");
  // One option per line reads as a table: not reflowed.
  // clang-format off
  options.add_options()
      ("shrink", tools::positiveValue(&g.shrink_factor, 100.0)->default_value(g.shrink_factor), "trimmed ICP shrink factor")
      ("min-distance", tools::rangedValue(&g.min_distance, 0.0)->default_value(g.min_distance), "trimmed ICP floor (m; 0: derived)")
      ("initial-distance", tools::rangedValue(&g.initial_distance, 0.0)->default_value(g.initial_distance),
       "method truth and fpfh-trimmed: the trimmed ICP's first limit (m; 0: 2 vote cells; the search's own last pass starts at 2 fine cells, 0.04)")
      ("inlier-distance", tools::rangedValue(&g.inlier_distance, 0.0)->default_value(g.inlier_distance), "inlier radius (m; 0: 2 target spacings)")
      ("yaw-hypotheses", tools::rangedValue(&g.yaw_hypotheses, 1u, 3600u)->default_value(g.yaw_hypotheses),
       "rotations (1-3600)")
      ("vote-cell", tools::positiveValue(&g.vote_cell)->default_value(g.vote_cell), "vote cell (m)")
      ("refined-hypotheses", tools::rangedValue(&g.refined_hypotheses, 1u, 360u)->default_value(g.refined_hypotheses),
       "best-voted hypotheses searched finely and refined (1-360)")
      ("climbed-hypotheses", tools::rangedValue(&g.climbed_hypotheses, 0u, 360u)->default_value(g.climbed_hypotheses),
       "best refined hypotheses searched again from where they ended while their inliers grow (0-360; 0: none)")
      ("climb-rounds", tools::rangedValue(&g.climb_rounds, 0u, 100u)->default_value(g.climb_rounds),
       "most times each is searched again (0-100)")
      ("tilted-hypotheses", tools::rangedValue(&g.tilted_hypotheses, 0u, 360u)->default_value(g.tilted_hypotheses),
       "best refined hypotheses tilted where the maps' up axes may disagree (0-360; 0: none)")
      ("final-tilt-range", tools::rangedValue(&g.final_tilt_range_deg, 0.0, 30.0)->default_value(g.final_tilt_range_deg),
       "the final pass also starts from the winner tilted this far (deg, 0-30; 0: none)")
      ("final-tilt-step", tools::rangedValue(&g.final_tilt_step_deg, 0.01, 30.0)->default_value(g.final_tilt_step_deg),
       "its step (deg; at most 10 steps each way)")
      ("final-tilt-rounds", tools::rangedValue(&g.final_tilt_rounds, 1u, 10u)->default_value(g.final_tilt_rounds),
       "rounds of final tilts, each about the last's winner while it lands in another basin and scores higher (1-10)")
      ("no-reverse", po::bool_switch()->notifier([&g](bool set) { g.reverse_larger_source = !set; }),
       "search a source much larger than the target as given, not the other way (GlobalAlignmentSettings::"
       "reverse_larger_source)");
  // clang-format on
  return options;
}

/// @brief The list options as given, parsed after the command line is read.
struct ListTexts {
  std::string overlaps = "0.33,0.5,0.67", yaws = "0,30,60,90,120,150,180", xy = "0:0,2:2,-2:1,1:-2,-2:-2", inside;
};

/// @brief The sweep's own options (the map, its pairs, the grid, the method), writing into `c` and `t`.
po::options_description sweepOptions(GlobalSweepCommand& c, ListTexts& t) {
  po::options_description options("wicp_global_sweep (--map FILE | --synthetic) [options]\nOptions");
  // One option per line reads as a table: not reflowed.
  // clang-format off
  options.add_options()
      ("help,h", "print this help")
      ("map", po::value(&c.map_path), "landmark map (paper format)")
      ("synthetic", po::bool_switch(&c.synthetic), "use a synthetic session's estimated map (simulation/session.h)")
      ("seed", tools::rangedValue(&c.seed, std::uint64_t{0})->default_value(c.seed), "synthetic session seed")
      ("landmarks", tools::rangedValue(&c.landmarks, std::size_t{1}, std::size_t{10000000})->default_value(c.landmarks),
       "synthetic landmarks placed (1-10000000)")
      ("overlaps", po::value(&t.overlaps)->default_value(t.overlaps), "overlap fractions, each in (0, 1]")
      ("disjoint", po::bool_switch(&c.disjoint), "deal out landmarks both mini-maps saw")
      ("halves", po::bool_switch(&c.halves), "add the alternate-landmark halves of the whole map")
      ("inside", po::value(&t.inside),
       "instead of the overlap pairs: mini-maps of these frame ranges FIRST-LAST (comma separated), each aligned "
       "onto the whole map")
      ("swap", po::bool_switch(&c.swap), "swap each pair's roles: the other map displaced and aligned (with --inside: "
       "the whole map onto each mini-map)")
      ("yaws", po::value(&t.yaws)->default_value(t.yaws), "yaw displacements, degrees")
      ("xy", po::value(&t.xy)->default_value(t.xy), "XY displacements x:y, comma separated")
      ("method", po::value(&c.method)->default_value(c.method),
       "global | coarse (the global search alone) | icp (today's, from the identity) | truth (trimmed ICP from the truth) "
       "| fpfh (PCL's FPFH + SampleConsensusPrerejective alone) | fpfh-trimmed (then the trimmed ICP)")
      ("min-observations", tools::rangedValue(&c.min_observations, std::size_t{0}, std::size_t{1000000})
                               ->default_value(c.min_observations), "as wicp_align")
      ("perturb", po::value(&c.perturb_text), "method truth: start this far from the truth")
      ("fpfh-radius-scale", tools::rangedValue(&c.fpfh_radius_scale, 0.1, 100.0)->default_value(c.fpfh_radius_scale),
       "methods fpfh*: multiply the normal (2 cells) and feature (5 cells) radii by this (0.1-100)")
      ("up-axis", po::value(&c.up_axis_text)->default_value(c.up_axis_text), "as wicp_align --global: auto, z or \"X Y Z\"")
      ("camera-frame", po::bool_switch(&c.camera_frame),
       "re-express the map in its first camera's frame (as a SLAM without gravity writes it); displacements stay "
       "rotations about the original z axis unless --map-pose places the new frame")
      ("tilt", tools::rangedValue(&c.tilt_deg, -90.0, 90.0)->default_value(c.tilt_deg),
       "re-express the map in a frame turned this many degrees about its x axis (a map written with its z axis "
       "that far off gravity, -90-90); displacements stay rotations about the original z axis")
      ("map-pose", po::value(&c.map_pose_text),
       "the map's frame in a z-up world, \"tx ty tz qx qy qz qw\" (a TUM trajectory line's order, e.g. the ground "
       "truth of the map's first frame): displacements are rotations about that world's z axis")
      ("verbose,v", po::bool_switch(&c.verbose), "one line per case");
  // clang-format on
  return options;
}

/// @brief Parses and checks the command line; false when only --help was asked for.
bool parseCommand(int argc, char** argv, GlobalSweepCommand& c) {
  ListTexts texts;
  po::options_description options = sweepOptions(c, texts);
  options.add(searchOptions(c.settings));
  po::variables_map vm;
  if (!tools::parseCommandLine(argc, argv, options, vm)) return false;
  if (c.synthetic == !c.map_path.empty()) throw po::error("give exactly one of --map FILE and --synthetic");
  if (c.method != "global" && c.method != "coarse" && c.method != "icp" && c.method != "truth" && c.method != "fpfh" &&
      c.method != "fpfh-trimmed")
    throw po::error("--method must be global, coarse, icp, truth, fpfh or fpfh-trimmed (got " + c.method + ")");
  c.overlaps = parseList(texts.overlaps, "overlaps");
  for (const double o : c.overlaps)
    if (!(o > 0.0 && o <= 1.0)) throw po::error("--overlaps: each must be in (0, 1] (got " + std::to_string(o) + ")");
  if (!texts.inside.empty()) c.inside = tools::parseFrameRanges(texts.inside, "--inside");
  c.yaws = parseList(texts.yaws, "yaws");
  c.xys = parseXyList(texts.xy);
  if (!c.perturb_text.empty()) Displacement::parse(c.perturb_text);  // refused now, not after the first pair
  try {
    c.up_axis = tools::parseUpAxisOption(c.up_axis_text);
  } catch (const std::invalid_argument& e) {
    throw po::error(std::string("--up-axis: ") + e.what());
  }
  if (!c.map_pose_text.empty()) c.world_from_map = parseTumPose(c.map_pose_text);
  if (c.tilt_deg != 0.0 && (c.camera_frame || !c.map_pose_text.empty()))
    throw po::error("--tilt re-expresses the map itself: not with --camera-frame or --map-pose");
  return true;
}

/// @brief The map pairs are cut from: the file, or a synthetic session's estimated map; with --camera-frame
/// re-expressed in its first camera's frame (and `c.world_from_map` set to that camera's pose), with --tilt in a
/// frame turned about x (and `c.world_from_map` set to that turn).
LandmarkMap loadMap(GlobalSweepCommand& c) {
  LandmarkMap map;
  if (!c.synthetic) {
    map = io::readLandmarkMap(c.map_path);
    if (map.frames.empty()) throw std::runtime_error(c.map_path + ": no frames to cut mini-maps from");
  } else {
    simulation::SyntheticSessionOptions session;
    session.seed = c.seed;
    session.num_landmarks = c.landmarks;
    map = simulation::generateSyntheticSession(session).estimated;
  }
  if (c.camera_frame) {
    const Eigen::Isometry3d first = map.toFirstCameraFrame();
    if (c.map_pose_text.empty()) c.world_from_map = first;  // turns about the original z axis
  }
  if (c.tilt_deg != 0.0) {
    Eigen::Isometry3d tilted = Eigen::Isometry3d::Identity();  // the new frame's axes in the map's
    tilted.linear() = Eigen::AngleAxisd(c.tilt_deg * M_PI / 180.0, Eigen::Vector3d::UnitX()).toRotationMatrix();
    map.transform(tilted.inverse());
    c.world_from_map = tilted;  // turns about the original z axis
  }
  return map;
}

/// @brief PCL's FPFH features matched by SampleConsensusPrerejective: the coarse stage issue #6 names as the
/// alternative to measure. Its lengths come from the same sample cell as GlobalAlignment's vote (vote_cell / 3)
/// with the ratios of PCL's alignment tutorial (normals within 2 cells, features within 5, inliers within 2.5);
/// the inlier fraction is 0.1, below the smallest overlap swept (0.2). Nothing here was tuned on the sweep.
class FpfhCoarseAligner {
 public:
  using Cloud = GlobalAlignment::Cloud;

  /// @param cell the voxel sample's cell
  /// @param radius_scale multiplies the normal and feature radii (1: the tutorial's ratios), to check that a
  ///        result is not an artefact of one choice
  /// @param target the target cloud
  FpfhCoarseAligner(double cell, double radius_scale, const Cloud& target)
      : cell_(cell), radius_scale_(radius_scale), target_(describe(target)) {}

  /// @brief The transformation taking `source` onto the target (identity when RANSAC found none), its time and
  /// the fraction of source samples it found a counterpart for.
  GlobalAlignmentResult align(const Cloud& source) const {
    const auto start = std::chrono::steady_clock::now();
    const Described described = describe(source);
    pcl::SampleConsensusPrerejective<pcl::PointXYZ, pcl::PointXYZ, pcl::FPFHSignature33> ransac;
    ransac.setInputSource(described.points);
    ransac.setSourceFeatures(described.features);
    ransac.setInputTarget(target_.points);
    ransac.setTargetFeatures(target_.features);
    ransac.setMaximumIterations(50000);
    ransac.setNumberOfSamples(3);
    ransac.setCorrespondenceRandomness(5);
    ransac.setSimilarityThreshold(0.9f);
    ransac.setMaxCorrespondenceDistance(2.5 * cell_);
    ransac.setInlierFraction(0.1f);
    std::srand(1);  // PCL's sample selection draws from rand(): the same samples on every run
    Cloud aligned;
    ransac.align(aligned);
    GlobalAlignmentResult result;
    if (ransac.hasConverged()) {
      result.transformation = ransac.getFinalTransformation().cast<double>();
      result.inliers = ransac.getInliers().size();
      result.inlier_fraction = static_cast<double>(result.inliers) / static_cast<double>(described.points->size());
    }
    result.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return result;
  }

 private:
  struct Described {
    Cloud::Ptr points;
    pcl::PointCloud<pcl::FPFHSignature33>::Ptr features;
  };

  /// Voxel sample, normals, FPFH features.
  Described describe(const Cloud& cloud) const {
    Described described{Cloud::Ptr(new Cloud),
                        pcl::PointCloud<pcl::FPFHSignature33>::Ptr(new pcl::PointCloud<pcl::FPFHSignature33>)};
    pcl::VoxelGrid<pcl::PointXYZ> grid;
    grid.setInputCloud(cloud.makeShared());
    grid.setLeafSize(static_cast<float>(cell_), static_cast<float>(cell_), static_cast<float>(cell_));
    grid.filter(*described.points);
    pcl::PointCloud<pcl::Normal>::Ptr normals(new pcl::PointCloud<pcl::Normal>);
    pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> normal_estimation;
    normal_estimation.setInputCloud(described.points);
    normal_estimation.setRadiusSearch(2.0 * radius_scale_ * cell_);
    normal_estimation.compute(*normals);
    pcl::FPFHEstimation<pcl::PointXYZ, pcl::Normal, pcl::FPFHSignature33> fpfh;
    fpfh.setInputCloud(described.points);
    fpfh.setInputNormals(normals);
    fpfh.setRadiusSearch(5.0 * radius_scale_ * cell_);
    fpfh.compute(*described.features);
    return described;
  }

  double cell_, radius_scale_;
  Described target_;
};

/// @brief The aligners of one pair, each given the pair's target once.
struct PairAligners {
  GlobalLandmarkAligner global;
  LandmarkAligner icp;
  GlobalAlignment trimmed;

  std::unique_ptr<FpfhCoarseAligner> fpfh;  // only for --method fpfh and fpfh-trimmed

  PairAligners(const GlobalAlignmentSettings& settings, const LandmarkCloud::Ptr& target, bool with_fpfh,
               double fpfh_radius_scale)
      : global(settings), icp(refinedIcp()), trimmed(settings) {
    global.setTarget(target);
    icp.setTarget(target);
    GlobalAlignment::Cloud target_xyz;
    pcl::copyPointCloud(*target, target_xyz);
    trimmed.setTarget(target_xyz);
    if (with_fpfh) fpfh = std::make_unique<FpfhCoarseAligner>(sampleCell(settings), fpfh_radius_scale, target_xyz);
  }

  /// GlobalAlignment's sample cell (its default: a third of the vote cell).
  static double sampleCell(const GlobalAlignmentSettings& settings) {
    return settings.sample_cell > 0.0 ? settings.sample_cell : settings.vote_cell / 3.0;
  }

  static AlignmentSettings refinedIcp() {
    AlignmentSettings plain;
    plain.refine = true;
    return plain;
  }
};

/// @brief One case's outcome against the truth.
struct CaseOutcome {
  double rotation_error_deg = 0.0, translation_error_m = 0.0, time_ms = 0.0, inlier_fraction = 0.0;
  bool good = false;
  /// Within the global search's fine window (fine_yaw_range_deg, fine_window): a coarse stage's result there is
  /// one the fine vote can take to the truth.
  bool in_fine_window = false;
};

/// @brief Displaces the pair's source by d and aligns it back by the chosen method.
CaseOutcome alignCase(const GlobalSweepCommand& c, PairAligners& aligners, const Pair& pair, const Displacement& d) {
  // d is made in the z-up world; in the map's frame it is conjugated by the map's pose there.
  const Eigen::Isometry3d displacement = c.world_from_map.inverse() * d.toIsometry() * c.world_from_map;
  LandmarkMap source = pair.source;
  source.transform(displacement);
  const LandmarkCloud::Ptr cloud = toLandmarkCloud(source, CovarianceWeight{});
  AlignmentResult result;
  CaseOutcome outcome;
  if (c.method == "global" || c.method == "coarse") {
    const auto r = aligners.global.align(cloud, tools::resolveUpAxes(c.up_axis, source, pair.target).axes);
    result = r.alignment;
    outcome.inlier_fraction = r.global.inlier_fraction;
    if (c.method == "coarse") result.transformation = r.global.transformation, result.time_ms = r.global.time_ms;
  } else if (c.method == "fpfh" || c.method == "fpfh-trimmed") {
    GlobalAlignment::Cloud xyz;
    pcl::copyPointCloud(*cloud, xyz);
    const GlobalAlignmentResult coarse = aligners.fpfh->align(xyz);
    result.transformation = coarse.transformation, result.time_ms = coarse.time_ms;
    outcome.inlier_fraction = coarse.inlier_fraction;
    if (c.method == "fpfh-trimmed") {  // the trimmed ICP from FPFH's start, as from our vote's
      const GlobalAlignmentResult refined = aligners.trimmed.refine(xyz, coarse.transformation);
      result.transformation = refined.transformation, result.time_ms += refined.time_ms;
      outcome.inlier_fraction = refined.inlier_fraction;
    }
  } else if (c.method == "truth") {  // the trimmed ICP alone, started at the truth
    GlobalAlignment::Cloud xyz;
    pcl::copyPointCloud(*cloud, xyz);
    const Eigen::Isometry3d off =
        c.perturb_text.empty() ? Eigen::Isometry3d::Identity() : Displacement::parse(c.perturb_text).toIsometry();
    const auto r = aligners.trimmed.refine(xyz, (off * displacement.inverse()).matrix());
    result.transformation = r.transformation, result.time_ms = r.time_ms;
    outcome.inlier_fraction = r.inlier_fraction;
    std::cout << "spacing " << r.target_spacing << " limit " << r.distance_limit << " median " << r.median_residual
              << '\n';
  } else {
    result = aligners.icp.align(cloud);
  }
  const Eigen::Isometry3d truth = displacement.inverse();
  const Eigen::Isometry3d estimate(result.transformation);
  outcome.rotation_error_deg = rotationErrorDeg(estimate, truth);
  outcome.translation_error_m = translationError(estimate, truth);
  outcome.time_ms = result.time_ms;
  outcome.good = outcome.rotation_error_deg <= kMaxRotationDeg && outcome.translation_error_m <= kMaxTranslationM;
  outcome.in_fine_window = outcome.rotation_error_deg <= c.settings.fine_yaw_range_deg &&
                           outcome.translation_error_m <= c.settings.fine_window;
  return outcome;
}

/// @brief Every displacement of the grid on one pair; prints the pair's line and returns its outcomes.
std::vector<CaseOutcome> sweepPair(const GlobalSweepCommand& c, const Pair& pair) {
  PairAligners aligners(c.settings, toLandmarkCloud(pair.target, CovarianceWeight{}),
                        c.method == "fpfh" || c.method == "fpfh-trimmed", c.fpfh_radius_scale);
  std::vector<CaseOutcome> outcomes;
  for (const double yaw : c.yaws)
    for (const auto& [x, y] : c.xys) {
      Displacement d;
      d.x = x, d.y = y, d.yaw_deg = yaw;
      const CaseOutcome o = alignCase(c, aligners, pair, d);
      outcomes.push_back(o);
      if (c.verbose)
        std::cout << pair.name << " yaw " << yaw << " xy " << x << "," << y << ": " << std::fixed
                  << std::setprecision(3) << o.rotation_error_deg << " deg " << o.translation_error_m * 100 << " cm "
                  << o.time_ms << " ms inl " << o.inlier_fraction << (o.good ? "" : "  FAIL") << std::defaultfloat
                  << '\n';
    }
  std::vector<double> rot, trans, times, overlap;
  std::size_t ok = 0, in_window = 0;
  for (const CaseOutcome& o : outcomes) {
    rot.push_back(o.rotation_error_deg), trans.push_back(o.translation_error_m), times.push_back(o.time_ms);
    overlap.push_back(o.inlier_fraction), ok += o.good ? 1 : 0, in_window += o.in_fine_window ? 1 : 0;
  }
  std::cout << std::fixed << std::setprecision(2) << pair.name << ": source " << pair.source.landmarks.size()
            << " target " << pair.target.landmarks.size() << " | " << ok << "/" << outcomes.size()
            << " within 2 deg 5 cm, " << in_window << " within the fine window | rot median " << median(rot) << " max "
            << quantile(rot, 1.0) << " deg | trans median " << median(trans) * 100 << " max "
            << quantile(trans, 1.0) * 100 << " cm | time median " << median(times) << " max " << quantile(times, 1.0)
            << " ms | inliers " << median(overlap) << std::defaultfloat << '\n';
  return outcomes;
}

}  // namespace

int main(int argc, char** argv) {
  return tools::runTool("wicp_global_sweep", [&] {
    GlobalSweepCommand command;
    if (!parseCommand(argc, argv, command)) return 0;
    const LandmarkMap map = loadMap(command);
    if (command.method == "global" || command.method == "coarse") {
      const auto [even, odd] = map.alternateHalves();  // every frame: the whole map's cameras
      std::cout << tools::resolveUpAxes(command.up_axis, odd, even).description << '\n';
    }
    auto pairs =
        makePairs(map, command.overlaps, command.inside, command.disjoint, command.halves, command.min_observations);
    if (command.swap)
      for (auto& pair : pairs) std::swap(pair.source, pair.target), pair.name += ", swapped";
    std::size_t total = 0, passed = 0, in_window = 0;
    std::vector<double> all_times;
    for (const auto& pair : pairs) {
      if (pair.source.landmarks.size() < 3 || pair.target.landmarks.size() < 3) {
        std::cout << pair.name << ": fewer than 3 landmarks on one side, skipped\n";
        continue;
      }
      for (const CaseOutcome& o : sweepPair(command, pair)) {
        ++total, passed += o.good ? 1 : 0, in_window += o.in_fine_window ? 1 : 0;
        all_times.push_back(o.time_ms);
      }
    }
    if (total == 0) throw std::runtime_error("no pair with at least 3 landmarks on each side: nothing measured");
    std::cout << "total " << passed << "/" << total << " within 2 deg 5 cm, " << in_window << "/" << total
              << " within the fine window (" << command.settings.fine_yaw_range_deg << " deg, "
              << command.settings.fine_window * 100 << " cm), median time " << median(all_times) << " ms\n";
    return 0;
  });
}
