// wicp_rgbd_slam: the RGB-D front end on a TUM sequence, or on the project's
// synthetic sequence when no --dataset is given. Writes, in --out DIR:
//   trajectory.txt  TUM format (timestamp tx ty tz qx qy qz qw), one line per tracked frame
//   minimaps/       mini-maps in the paper's map format, ready for wicp_align
//   session.txt     the whole session map in the same format
//   map.ply         landmarks with weights and raw metrics
//   report.json     counts, timing, skipped frames, ATE when ground truth exists

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <optional>
#include <sstream>

#include <boost/program_options.hpp>

#include "tool_support.h"
#include "weighted_icp/core/statistics.h"
#include "weighted_icp/frontend/slam/rgbd_slam.h"
#include "weighted_icp/io/cloud_io.h"
#include "weighted_icp/io/map_format.h"
#include "weighted_icp/io/trajectory.h"
#include "weighted_icp/io/tum_sequence.h"
#include "weighted_icp/metrics/trajectory_error.h"
#include "weighted_icp/registration/landmark_point.h"
#include "weighted_icp/simulation/rgbd_sequence.h"

namespace po = boost::program_options;
namespace fs = std::filesystem;
using namespace weighted_icp;

namespace {

/// Where frames come from: a TUM folder or the synthetic generator.
class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual std::size_t size() const = 0;
  virtual RgbdFrame load(std::size_t i) const = 0;
  virtual Trajectory groundTruth() const = 0;
  virtual const PinholeCamera& camera() const = 0;
  virtual std::string describe() const = 0;
};

class TumSource : public FrameSource {
 public:
  TumSource(const std::string& dir, PinholeCamera camera) : sequence_(io::TumSequence::open(dir)), camera_(camera) {}
  std::size_t size() const override { return sequence_.size(); }
  RgbdFrame load(std::size_t i) const override {
    RgbdFrame images = sequence_.loadFrame(i, camera_);
    if (images.validDepthPixels() == 0)
      std::cerr << "wicp_rgbd_slam: warning: " << sequence_.frame(i).depth_path << " has no valid depth; frame " << i
                << " is tracked without it\n";
    return images;
  }
  Trajectory groundTruth() const override { return sequence_.groundTruth(); }
  const PinholeCamera& camera() const override { return camera_; }
  std::string describe() const override { return "TUM sequence " + sequence_.directory(); }

 private:
  io::TumSequence sequence_;
  PinholeCamera camera_;
};

class SyntheticSource : public FrameSource {
 public:
  explicit SyntheticSource(const simulation::SyntheticRgbdOptions& options) : sequence_(options) {}
  std::size_t size() const override { return sequence_.size(); }
  RgbdFrame load(std::size_t i) const override { return sequence_.frame(i).rgbd; }
  Trajectory groundTruth() const override {
    Trajectory truth;
    for (std::size_t i = 0; i < sequence_.size(); ++i)
      truth.push_back({sequence_.timestamp(i), sequence_.cameraToWorld(i)});
    return truth;
  }
  const PinholeCamera& camera() const override { return sequence_.options().camera; }
  std::string describe() const override {
    std::ostringstream out;
    out << "synthetic sequence (seed " << sequence_.options().seed
        << (sequence_.options().moving_object ? ", moving object" : "")
        << (sequence_.options().dim_lighting ? ", dim lighting" : "") << ")";
    return out.str();
  }

 private:
  simulation::SyntheticRgbdSequence sequence_;
};

/// TUM folders are named after their sensor (rgbd_dataset_freiburg3_teddy, tum_fr1_xyz_head).
std::string cameraFromFolderName(const std::string& dir) {
  // The folder's own name only ("data/", "data/." and "data" alike), not its parents'.
  const std::string name = fs::weakly_canonical(fs::absolute(dir)).filename().string();
  for (const char* sensor : {"1", "2", "3"})
    if (name.find(std::string("freiburg") + sensor) != std::string::npos ||
        name.find(std::string("fr") + sensor) != std::string::npos)
      return std::string("fr") + sensor;
  throw std::runtime_error("cannot tell the camera of " + dir + " from its name; pass --camera fr1|fr2|fr3|FILE.yaml");
}

/// A quantile of the per-frame times; 0 when no frame was timed.
double percentile(const std::vector<double>& values, double q) { return values.empty() ? 0.0 : quantile(values, q); }

}  // namespace

int main(int argc, char** argv) {
  return tools::runTool("wicp_rgbd_slam", [&] {
    std::string dataset, camera_spec, out_dir, matcher_name = "flann";
    std::size_t max_frames = 0;
    frontend::RgbdSlamOptions options;
    simulation::SyntheticRgbdOptions synthetic;
    po::options_description description(
        "wicp_rgbd_slam [--dataset DIR] [--camera fr1|fr2|fr3|FILE.yaml] [--max-frames N]\n"
        "               [--minimap-keyframes N] --out DIR\n"
        "Feature-based RGB-D SLAM producing weighted landmark maps. Options");
    // One option per line reads as a table: not reflowed.
    // clang-format off
    description.add_options()
        ("help,h", "print this help")
        ("dataset", po::value(&dataset), "TUM RGB-D folder (rgb.txt, depth.txt, optional groundtruth.txt); "
                                         "default: the synthetic sequence")
        ("camera", po::value(&camera_spec), "fr1, fr2, fr3 or a camera YAML; default: from the folder name")
        ("max-frames", tools::rangedValue(&max_frames, std::size_t{0})->default_value(0), "stop after N frames (0 = all)")
        ("minimap-keyframes", tools::rangedValue(&options.minimap_keyframes, std::size_t{1}, std::size_t{100000})
                                  ->default_value(options.minimap_keyframes),
         "keyframes per mini-map (1-100000)")
        ("out", po::value(&out_dir)->required(), "output folder (created)")
        ("matcher", po::value(&matcher_name)->default_value(matcher_name), "flann (LSH) or brute-force")
        ("no-quality-gate", "do not skip frames by BRISQUE score")
        ("deterministic", "run bundle adjustment inline instead of in its own thread (reproducible)")
        ("synthetic-frames", tools::rangedValue(&synthetic.frames, std::size_t{1}, std::size_t{100000})
                                 ->default_value(synthetic.frames),
         "synthetic: frames (1-100000)")
        ("seed", tools::rangedValue(&synthetic.seed, std::uint64_t{0})->default_value(synthetic.seed), "synthetic: seed")
        ("moving-object", po::bool_switch(&synthetic.moving_object), "synthetic: a box moves through the view")
        ("dim", po::bool_switch(&synthetic.dim_lighting), "synthetic: dim, low-contrast, noisy images");
    // clang-format on
    po::variables_map vm;
    if (!tools::parseCommandLine(argc, argv, description, vm)) return 0;
    options.frontend.matcher.kind = frontend::parseMatcherKind(matcher_name);
    options.frontend.quality_gate = !vm.count("no-quality-gate");
    options.backend.background_thread = !vm.count("deterministic");

    std::unique_ptr<FrameSource> source;
    if (dataset.empty()) {
      source = std::make_unique<SyntheticSource>(synthetic);
    } else {
      const std::string spec = camera_spec.empty() ? cameraFromFolderName(dataset) : camera_spec;
      source = std::make_unique<TumSource>(dataset, io::loadCamera(spec));
    }
    const std::size_t frames = max_frames > 0 ? std::min(max_frames, source->size()) : source->size();
    std::cout << "running on " << source->describe() << ", " << frames << " frames\n";
    fs::create_directories(fs::path(out_dir) / "minimaps");

    frontend::RgbdSlam slam(source->camera(), options);
    tools::Progress progress("tracking", frames);
    std::size_t unreadable = 0;
    for (std::size_t i = 0; i < frames; ++i) {
      RgbdFrame image;
      try {
        image = source->load(i);
      } catch (const std::exception& e) {
        // A bad frame is reported and skipped; what is mapped stays.
        std::cerr << "wicp_rgbd_slam: warning: frame " << i << " skipped: " << e.what() << '\n';
        ++unreadable;
        progress.step();
        continue;
      }
      const auto& record = slam.process(image);
      progress.step(frontend::toString(record.result.status) + ", " + std::to_string(record.result.inliers) +
                    " inliers");
    }
    progress.finish();
    slam.finish();

    // Outputs, each written atomically.
    const Trajectory trajectory = slam.trajectory();
    io::writeTrajectory(trajectory, (fs::path(out_dir) / "trajectory.txt").string());
    const LandmarkMap session = slam.sessionMap();
    io::writeLandmarkMap(session, (fs::path(out_dir) / "session.txt").string());
    const std::vector<LandmarkMap> minimaps = slam.miniMaps();
    for (std::size_t m = 0; m < minimaps.size(); ++m) {
      std::ostringstream name;
      name << "minimap_" << std::setw(3) << std::setfill('0') << m << ".txt";
      io::writeLandmarkMap(minimaps[m], (fs::path(out_dir) / "minimaps" / name.str()).string());
    }
    if (!session.landmarks.empty())
      io::saveLandmarkCloud(*toLandmarkCloud(session, CovarianceWeight{}), (fs::path(out_dir) / "map.ply").string());

    std::vector<double> tracking_ms;
    std::size_t tracked = 0, skipped = 0, lost = 0, clahe = 0, dynamic = 0;
    for (const auto& record : slam.frames()) {
      tracking_ms.push_back(record.tracking_ms);
      tracked += record.result.hasPose();
      skipped += record.result.refused_by_quality_gate;
      lost += record.result.status == frontend::TrackingStatus::Lost;
      clahe += record.result.used_clahe;
      dynamic += record.result.dynamic;
    }
    tools::JsonObject report;
    report.add("source", source->describe())
        .add("frames", frames)
        .add("tracked_frames", tracked)
        .add("keyframes", slam.map().keyframeCount())
        .add("landmarks", slam.map().mapPointCount())
        .add("minimaps", minimaps.size())
        .add("median_ms_per_frame", percentile(tracking_ms, 0.5))
        .add("p90_ms_per_frame", percentile(tracking_ms, 0.9))
        .add("skipped_frames", skipped)
        .add("unreadable_frames", unreadable)
        .add("lost_frames", lost)
        .add("clahe_frames", clahe)
        .add("dynamic_matches", dynamic)
        .add("bundle_adjustments", slam.optimizationsRun());
    const Trajectory truth = source->groundTruth();
    std::optional<metrics::AbsoluteTrajectoryError> ate;
    if (!truth.empty() && trajectory.size() >= 3) {
      ate = metrics::computeAte(truth, trajectory);
      report.add("ate_rmse_m", ate->translation.rmse).add("ate_pairs", ate->pairs);
    }
    tools::writeTextFile((fs::path(out_dir) / "report.json").string(), report.str() + "\n");

    std::cout << std::fixed << std::setprecision(1) << "tracked " << tracked << "/" << frames << " frames, "
              << slam.map().keyframeCount() << " keyframes, " << slam.map().mapPointCount() << " landmarks, "
              << minimaps.size() << " mini-maps; median " << percentile(tracking_ms, 0.5) << " ms/frame (p90 "
              << percentile(tracking_ms, 0.9) << "); skipped " << skipped << ", lost " << lost << '\n';
    if (ate)
      std::cout << std::setprecision(2) << "ATE RMSE " << ate->translation.rmse * 100 << " cm over " << ate->pairs
                << " poses\n";
    std::cout << "wrote " << out_dir << "/{trajectory.txt, session.txt, minimaps/, map.ply, report.json}\n";
    return tracked > 0 ? 0 : 1;
  });
}
