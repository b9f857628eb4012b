// wicp_global_sweep: measures alignment from any start on partial-overlap
// pairs cut from one map (real or synthetic) with exact truth, over a grid of
// yaw and XY displacements: success rate, errors and time per alignment.
//
// Pairs: for each overlap fraction o, mini-maps A = frames [0, L) and
// B = frames [F - L, F) of the F-frame map, L = F / (2 - o), so a fraction o
// of each one's frames is shared; with --disjoint the landmarks both saw are
// dealt out by id parity, so no landmark is in both. --halves adds the
// alternate-landmark halves of the whole map. B is displaced and aligned onto A.

#include <cmath>
#include <iomanip>
#include <iostream>
#include <set>
#include <sstream>

#include <boost/program_options.hpp>

#include <pcl/common/io.h>

#include "tool_support.h"
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

std::vector<double> parseList(const std::string& text) {
  std::vector<double> values;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) values.push_back(std::stod(item));
  return values;
}

/// Landmarks seen by both maps go to one of them only, by id parity.
void makeDisjoint(LandmarkMap& a, LandmarkMap& b) {
  std::set<LandmarkId> in_a, in_b;
  for (const auto& l : a.landmarks) in_a.insert(l.id);
  for (const auto& l : b.landmarks) in_b.insert(l.id);
  const auto drop = [](LandmarkMap& map, const std::set<LandmarkId>& other, int parity) {
    std::vector<Landmark> kept;
    for (auto& l : map.landmarks)
      if (!other.count(l.id) || static_cast<int>(l.id % 2) == parity) kept.push_back(std::move(l));
    map.landmarks = std::move(kept);
  };
  drop(a, in_b, 0);
  drop(b, in_a, 1);
}

std::vector<Pair> makePairs(const LandmarkMap& map, const std::vector<double>& overlaps, bool disjoint, bool halves,
                            std::size_t min_observations) {
  std::vector<Pair> pairs;
  const FrameId first = map.frames.begin()->first, last = map.frames.rbegin()->first;
  const double frames = static_cast<double>(last - first + 1);
  for (double o : overlaps) {
    const auto length = static_cast<FrameId>(std::llround(frames / (2.0 - o)));
    LandmarkMap a = map.miniMap(first, first + length - 1), b = map.miniMap(last - length + 1, last);
    if (disjoint) makeDisjoint(a, b);
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

}  // namespace

int main(int argc, char** argv) {
  return tools::runTool("wicp_global_sweep", [&] {
    std::string map_path, overlaps_text = "0.33,0.5,0.67", yaws_text = "0,30,60,90,120,150,180", method = "global";
    std::string xy_text = "0:0,2:2,-2:1,1:-2,-2:-2";
    std::uint64_t seed = 1;
    std::size_t landmarks = 8000, min_observations = 2;
    double max_rotation = 2.0, max_translation = 0.05;
    GlobalAlignmentSettings settings;
    std::string perturb_text;
    po::options_description options("wicp_global_sweep (--map FILE | --synthetic) [options]\nOptions");
    // clang-format off
    options.add_options()
        ("help,h", "print this help")
        ("map", po::value(&map_path), "landmark map (paper format)")
        ("synthetic", "use a synthetic session's estimated map (simulation/session.h)")
        ("seed", po::value(&seed)->default_value(seed), "synthetic session seed")
        ("landmarks", po::value(&landmarks)->default_value(landmarks), "synthetic landmarks placed")
        ("overlaps", po::value(&overlaps_text)->default_value(overlaps_text), "overlap fractions")
        ("disjoint", "deal out landmarks both mini-maps saw")
        ("halves", "add the alternate-landmark halves of the whole map")
        ("yaws", po::value(&yaws_text)->default_value(yaws_text), "yaw displacements, degrees")
        ("xy", po::value(&xy_text)->default_value(xy_text), "XY displacements x:y, comma separated")
        ("method", po::value(&method)->default_value(method), "global | icp (today's, from the identity)")
        ("min-observations", po::value(&min_observations)->default_value(min_observations), "as wicp_align")
        ("shrink", po::value(&settings.shrink_factor)->default_value(settings.shrink_factor), "trimmed ICP shrink factor")
        ("min-distance", po::value(&settings.min_distance)->default_value(settings.min_distance), "trimmed ICP floor")
        ("inlier-distance", po::value(&settings.inlier_distance)->default_value(settings.inlier_distance), "inlier radius")
        ("yaw-hypotheses", po::value(&settings.yaw_hypotheses)->default_value(settings.yaw_hypotheses), "rotations")
        ("vote-cell", po::value(&settings.vote_cell)->default_value(settings.vote_cell), "vote cell")
        ("perturb", po::value(&perturb_text), "method truth: start this far from the truth")
        ("verbose,v", "one line per case");
    // clang-format on
    po::variables_map vm;
    if (!tools::parseCommandLine(argc, argv, options, vm)) return 0;
    LandmarkMap map;
    if (vm.count("synthetic")) {
      simulation::SyntheticSessionOptions session;
      session.seed = seed;
      session.num_landmarks = landmarks;
      map = simulation::generateSyntheticSession(session).estimated;
    } else {
      map = io::readLandmarkMap(map_path);
    }
    std::vector<std::pair<double, double>> xys;
    for (std::stringstream in(xy_text); in.good();) {
      std::string item;
      std::getline(in, item, ',');
      const auto colon = item.find(':');
      xys.emplace_back(std::stod(item.substr(0, colon)), std::stod(item.substr(colon + 1)));
    }
    const auto pairs =
        makePairs(map, parseList(overlaps_text), vm.count("disjoint") > 0, vm.count("halves") > 0, min_observations);
    std::size_t total = 0, passed = 0;
    std::vector<double> all_times;
    for (const auto& pair : pairs) {
      const LandmarkCloud::Ptr target = toLandmarkCloud(pair.target, CovarianceWeight{});
      GlobalLandmarkAligner global(settings);
      global.setTarget(target);
      AlignmentSettings plain;
      plain.refine = true;
      LandmarkAligner icp(plain);
      GlobalAlignment trimmed(settings);
      GlobalAlignment::Cloud target_xyz;
      pcl::copyPointCloud(*target, target_xyz);
      trimmed.setTarget(target_xyz);
      icp.setTarget(target);
      std::size_t ok = 0, n = 0;
      std::vector<double> rot, trans, times, overlap;
      for (double yaw : parseList(yaws_text))
        for (const auto& [x, y] : xys) {
          Displacement d;
          d.x = x, d.y = y, d.yaw_deg = yaw;
          LandmarkMap source = pair.source;
          source.transform(d.toIsometry());
          const LandmarkCloud::Ptr cloud = toLandmarkCloud(source, CovarianceWeight{});
          AlignmentResult result;
          double inlier_fraction = 0.0;
          if (method == "global" || method == "coarse") {
            const auto r = global.align(cloud);
            result = r.alignment;
            inlier_fraction = r.global.inlier_fraction;
            if (method == "coarse") result.transformation = r.global.transformation, result.time_ms = r.global.time_ms;
          } else if (method == "truth") {  // the trimmed ICP alone, started at the truth
            GlobalAlignment::Cloud xyz;
            pcl::copyPointCloud(*cloud, xyz);
            const Eigen::Isometry3d off =
                perturb_text.empty() ? Eigen::Isometry3d::Identity() : Displacement::parse(perturb_text).toIsometry();
            const auto r = trimmed.refine(xyz, (off * d.toIsometry().inverse()).matrix());
            result.transformation = r.transformation, result.time_ms = r.time_ms;
            inlier_fraction = r.inlier_fraction;
            std::cout << "spacing " << r.target_spacing << " limit " << r.distance_limit << " median "
                      << r.median_residual << '\n';
          } else {
            result = icp.align(cloud);
          }
          const Eigen::Isometry3d truth = d.toIsometry().inverse();
          const Eigen::Isometry3d estimate(result.transformation);
          const double re = rotationErrorDeg(estimate, truth), te = translationError(estimate, truth);
          const bool good = re <= max_rotation && te <= max_translation;
          ok += good, ++n;
          rot.push_back(re), trans.push_back(te), times.push_back(result.time_ms), overlap.push_back(inlier_fraction);
          if (vm.count("verbose"))
            std::cout << pair.name << " yaw " << yaw << " xy " << x << "," << y << ": " << std::fixed
                      << std::setprecision(3) << re << " deg " << te * 100 << " cm " << result.time_ms << " ms inl "
                      << inlier_fraction << (good ? "" : "  FAIL") << std::defaultfloat << '\n';
        }
      total += n, passed += ok;
      all_times.insert(all_times.end(), times.begin(), times.end());
      std::cout << std::fixed << std::setprecision(2) << pair.name << ": source " << pair.source.landmarks.size()
                << " target " << pair.target.landmarks.size() << " | " << ok << "/" << n
                << " within 2 deg 5 cm | rot median " << median(rot) << " max " << quantile(rot, 1.0)
                << " deg | trans median " << median(trans) * 100 << " max " << quantile(trans, 1.0) * 100
                << " cm | time median " << median(times) << " max " << quantile(times, 1.0) << " ms | inliers "
                << median(overlap) << std::defaultfloat << '\n';
    }
    std::cout << "total " << passed << "/" << total << " within 2 deg 5 cm, median time " << median(all_times)
              << " ms\n";
    return 0;
  });
}
