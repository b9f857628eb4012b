// wicp_map: inspects and prepares landmark maps in the paper's map format.
//   stats    counts, observation histogram, extents and metric/weight distributions
//   cut      mini-maps of consecutive frames, the units the paper's experiments align
//   convert  a weighted LandmarkCloud as PCD or PLY
//
// Exit codes (tools::runTool): 0 done, 1 bad data (the message names file and
// line), 2 bad command line.

#include <algorithm>
#include <array>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <limits>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <boost/program_options.hpp>

#include "frame_ranges.h"
#include "tool_support.h"
#include "weighted_icp/core/statistics.h"
#include "weighted_icp/io/cloud_io.h"
#include "weighted_icp/io/map_format.h"
#include "weighted_icp/registration/landmark_point.h"
#include "weighted_icp/registration/weight_strategies.h"

namespace po = boost::program_options;
namespace fs = std::filesystem;
using namespace weighted_icp;

namespace {

const char* const kUsage = "usage: wicp_map stats|cut|convert MAP [options]   (wicp_map COMMAND --help for each)";

/// Parses one command's arguments; argv[0] is the command's name. The
/// positional arguments are declared in `positional_options` and explained in
/// the usage line of `visible`, which alone --help prints. Returns false after
/// printing the help.
bool parseArguments(int argc, char** argv, const std::string& usage, po::options_description& visible,
                    const po::options_description& positional_options,
                    const po::positional_options_description& positional, po::variables_map& vm) {
  visible.add_options()("help,h", "print this help");
  po::options_description all;
  all.add(visible).add(positional_options);
  po::store(po::command_line_parser(argc, argv).options(all).positional(positional).run(), vm);
  if (vm.count("help")) {
    std::cout << visible << '\n';
    return false;
  }
  // notify() would say "the option '--map' is required": there is no such
  // option, so a missing positional argument is named as the usage line does.
  for (unsigned i = 0; i < positional.max_total_count(); ++i) {
    const std::string& name = positional.name_for_position(i);
    if (!vm.count(name))
      throw po::error(std::string(argv[0]) + ": " + positional_options.find(name, false).description() +
                      " is required (usage: " + usage + ")");
  }
  po::notify(vm);
  return true;
}

void printDistribution(const std::string& label, std::vector<double> values) {
  std::sort(values.begin(), values.end());
  std::cout << "  " << std::left << std::setw(30) << label << std::right;
  for (const double p : {0.0, 0.5, 0.9, 1.0}) std::cout << std::setw(13) << quantileOfSorted(values, p);
  std::cout << '\n';
}

/// The histogram of observations per landmark, in buckets 0, 1, 2, 3, 4, 5-9, 10+.
void printObservationHistogram(const LandmarkMap& map) {
  std::array<std::size_t, 7> histogram{};
  for (const auto& landmark : map.landmarks) {
    const std::size_t n = landmark.observations.size();
    ++histogram[n < 5 ? n : n < 10 ? 5 : 6];
  }
  const std::array<const char*, 7> bucket_names{"0", "1", "2", "3", "4", "5-9", "10+"};
  std::cout << "observations per landmark:";
  for (std::size_t i = 0; i < histogram.size(); ++i) std::cout << "  " << bucket_names[i] << ": " << histogram[i];
  std::cout << '\n';
}

/// The bounding box of `selected` (not empty) and the distributions of its covariance norms, mean observation
/// distances and each strategy's weights.
void printSelectedLandmarks(const LandmarkMap& selected) {
  Eigen::Vector3d low = selected.landmarks.front().position, high = low;
  std::vector<double> covariance_norms, mean_distances;
  for (const auto& landmark : selected.landmarks) {
    low = low.cwiseMin(landmark.position);
    high = high.cwiseMax(landmark.position);
    covariance_norms.push_back(landmark.covariance.norm());
    mean_distances.push_back(selected.meanObservationDistance(landmark));
  }
  const Eigen::IOFormat row(Eigen::StreamPrecision, Eigen::DontAlignCols, " ", " ", "", "", "(", ")");
  std::cout << "over these " << selected.landmarks.size() << " landmarks:\n"
            << "  bounding box  min " << low.transpose().format(row) << "  max " << high.transpose().format(row)
            << "  size " << (high - low).transpose().format(row) << " m\n"
            << "  " << std::setw(30) << "" << std::setw(13) << "min" << std::setw(13) << "median" << std::setw(13)
            << "p90" << std::setw(13) << "max" << '\n';
  printDistribution("covariance norm (Frobenius)", covariance_norms);
  printDistribution("mean observation distance (m)", mean_distances);
  for (const WeightStrategy strategy : allWeightStrategies())
    printDistribution("weight " + toString(strategy), computeWeights(selected, weightFunction(strategy)));
}

int stats(int argc, char** argv) {
  std::string map_path;
  std::size_t min_count = 2;
  const std::string usage = "wicp_map stats MAP [--min-observations N]";
  po::options_description visible(
      usage +
      "\n"
      "Frames, landmarks and their histogram of observation counts; then, over the landmarks\n"
      "with >= N observations, the bounding box and min/median/90th percentile/max of the\n"
      "covariance Frobenius norm, the mean observation distance and each strategy's weight.\n"
      "Options");
  visible.add_options()("min-observations", tools::rangedValue(&min_count, std::size_t{0})->default_value(min_count),
                        "landmarks the extents and distributions are over (the paper aligns those with >= 2)");
  po::options_description positional_options;
  positional_options.add_options()("map", po::value(&map_path)->required(), "a MAP file");
  po::positional_options_description positional;
  positional.add("map", 1);
  po::variables_map vm;
  if (!parseArguments(argc, argv, usage, visible, positional_options, positional, vm)) return 0;

  const LandmarkMap map = io::readLandmarkMap(map_path);
  std::cout << "map         " << map_path << '\n' << "frames      " << map.frames.size();
  if (!map.frames.empty())
    std::cout << " (ids " << map.frames.begin()->first << '-' << map.frames.rbegin()->first << ')';
  std::cout << '\n' << "landmarks   " << map.landmarks.size() << '\n';

  printObservationHistogram(map);

  const LandmarkMap selected = map.withMinObservations(min_count);
  std::cout << "landmarks with >= " << min_count << " observations: " << selected.landmarks.size() << '\n';
  if (selected.landmarks.empty()) return 0;

  printSelectedLandmarks(selected);
  return 0;
}

std::string miniMapName(std::size_t index) {
  std::ostringstream name;
  name << "minimap_" << std::setw(3) << std::setfill('0') << index << ".txt";
  return name.str();
}

/// @brief The mini-maps of `map`: consecutive runs of `frames_per_minimap` frames, or one per range of `ranges`
/// when it is not empty (a range without a frame of the map is an error naming `map_path`).
std::vector<LandmarkMap> cutMiniMaps(const LandmarkMap& map, const std::string& map_path,
                                     std::size_t frames_per_minimap, const std::vector<tools::FrameRange>& ranges) {
  if (ranges.empty()) return map.splitIntoMiniMaps(frames_per_minimap);
  std::vector<LandmarkMap> minis;
  for (const auto& range : ranges) {
    LandmarkMap mini = map.miniMap(range.first, range.last);
    if (mini.frames.empty())
      throw std::runtime_error(map_path + " has no frame in the range " + std::to_string(range.first) + "-" +
                               std::to_string(range.last));
    minis.push_back(std::move(mini));
  }
  return minis;
}

int cut(int argc, char** argv) {
  std::string map_path, out_dir, ranges_text;
  std::size_t frames_per_minimap = 0, min_count = 1;
  const std::string usage =
      "wicp_map cut MAP --out DIR (--frames-per-minimap N | --ranges \"0-119,120-239\") [--min-observations N] "
      "[--overwrite]";
  po::options_description visible(
      usage +
      "\n"
      "Writes DIR/minimap_000.txt, ... in the map format: the frames of each mini-map and every landmark\n"
      "they saw, with only their observations (LandmarkMap::miniMap). DIR holds one whole cut: it is written\n"
      "under a temporary name and renamed, so a failed cut leaves it as it was. Options");
  // One option per line reads as a table: not reflowed.
  // clang-format off
  visible.add_options()
      ("out", po::value(&out_dir)->required(), "output folder (created if missing; refused if not empty)")
      ("overwrite", "replace DIR if it is not empty (no earlier mini-map is left in it)")
      ("frames-per-minimap", tools::rangedValue(&frames_per_minimap, std::size_t{1}),
       "consecutive frames per mini-map, in frame-id order; the last may be shorter")
      ("ranges", po::value(&ranges_text), "frame-id ranges FIRST-LAST, comma separated; may overlap")
      ("min-observations", tools::rangedValue(&min_count, std::size_t{0})->default_value(min_count),
       "drop landmarks observed fewer times within the mini-map; 1 keeps every landmark it saw "
       "(0 is the same: a mini-map has no landmark it did not see)");
  // clang-format on
  po::options_description positional_options;
  positional_options.add_options()("map", po::value(&map_path)->required(), "a MAP file");
  po::positional_options_description positional;
  positional.add("map", 1);
  po::variables_map vm;
  if (!parseArguments(argc, argv, usage, visible, positional_options, positional, vm)) return 0;
  if (vm.count("frames-per-minimap") == vm.count("ranges"))
    throw po::error("give either --frames-per-minimap or --ranges");
  const std::vector<tools::FrameRange> ranges =
      vm.count("ranges") ? tools::parseFrameRanges(ranges_text, "--ranges") : std::vector<tools::FrameRange>{};

  const LandmarkMap map = io::readLandmarkMap(map_path);
  const std::vector<LandmarkMap> minis = cutMiniMaps(map, map_path, frames_per_minimap, ranges);
  if (minis.empty()) {
    std::cout << map_path << " has no frames: no mini-map written\n";
    return 0;
  }

  // Every mini-map is written before any is shown: the folder appears whole or not at all.
  io::AtomicFolder folder = tools::openOutputFolder(out_dir, vm.count("overwrite") > 0);
  std::ostringstream written;
  for (std::size_t i = 0; i < minis.size(); ++i) {
    const LandmarkMap mini = minis[i].withMinObservations(min_count);
    io::writeLandmarkMap(mini, (folder.path() / miniMapName(i)).string());
    written << (folder.target() / miniMapName(i)).string() << "  frames " << mini.frames.begin()->first << '-'
            << mini.frames.rbegin()->first << " (" << mini.frames.size() << " frames)  " << mini.landmarks.size()
            << " landmarks\n";
  }
  folder.publish();
  std::cout << written.str();
  return 0;
}

/// A cloud stores positions as float: a landmark beyond its range would be
/// written as infinity, which no loader accepts, so it is refused by id.
void requireFloatPositions(const LandmarkMap& map, const std::string& map_path) {
  const double limit = std::numeric_limits<float>::max();
  for (const auto& landmark : map.landmarks)
    if ((landmark.position.array().abs() > limit).any()) {
      std::ostringstream position;
      position << landmark.position.transpose().format(Eigen::IOFormat(Eigen::StreamPrecision, Eigen::DontAlignCols));
      throw std::runtime_error(map_path + ": landmark " + std::to_string(landmark.id) + " at (" + position.str() +
                               ") is beyond a point cloud's float range; not converting");
    }
}

int convert(int argc, char** argv) {
  std::string map_path, output_path, strategy_name = "covariance";
  std::size_t min_count = 2;
  const std::string usage = "wicp_map convert MAP OUT.pcd|OUT.ply [--strategy covariance] [--min-observations 2]";
  po::options_description visible(
      usage +
      "\n"
      "Saves the landmarks as a weighted LandmarkCloud (x y z weight covariance_norm\n"
      "mean_observation_distance num_observations). A map without landmarks gives an empty\n"
      "cloud, which only PCD can hold. Options");
  // One option per line reads as a table: not reflowed.
  // clang-format off
  visible.add_options()
      ("strategy", po::value(&strategy_name)->default_value(strategy_name),
       "weight: base, covariance, observations, mean-distance")
      ("min-observations", tools::rangedValue(&min_count, std::size_t{0})->default_value(min_count),
       "drop landmarks observed fewer times (the paper uses 2)");
  // clang-format on
  po::options_description positional_options;
  // One option per line reads as a table: not reflowed.
  // clang-format off
  positional_options.add_options()
      ("map", po::value(&map_path)->required(), "a MAP file")
      ("output", po::value(&output_path)->required(), "an output cloud OUT.pcd|OUT.ply");
  // clang-format on
  po::positional_options_description positional;
  positional.add("map", 1).add("output", 1);
  po::variables_map vm;
  if (!parseArguments(argc, argv, usage, visible, positional_options, positional, vm)) return 0;
  WeightStrategy strategy = WeightStrategy::Covariance;
  try {
    strategy = parseWeightStrategy(strategy_name);
  } catch (const std::invalid_argument& e) {
    throw po::error(std::string("--strategy: ") + e.what());
  }

  const LandmarkMap map = io::readLandmarkMap(map_path).withMinObservations(min_count);
  requireFloatPositions(map, map_path);
  const LandmarkCloud::Ptr cloud = toLandmarkCloud(map, weightFunction(strategy));
  io::saveLandmarkCloud(*cloud, output_path);
  std::cout << output_path << ": " << cloud->size() << " landmarks with >= " << min_count << " observations, weight "
            << toString(strategy) << '\n';
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return tools::runTool("wicp_map", [&] {
    const std::string command = argc > 1 ? argv[1] : "";
    if (command == "--help" || command == "-h") {
      std::cout << kUsage << '\n';
      return 0;
    }
    if (command == "stats") return stats(argc - 1, argv + 1);
    if (command == "cut") return cut(argc - 1, argv + 1);
    if (command == "convert") return convert(argc - 1, argv + 1);
    throw po::error(command.empty() ? std::string("no command given; ") + kUsage
                                    : "unknown command '" + command + "'; " + kUsage);
  });
}
