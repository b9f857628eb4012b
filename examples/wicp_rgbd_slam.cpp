// wicp_rgbd_slam: the RGB-D front end on a TUM sequence, or on the project's
// synthetic sequence when no --dataset is given. Writes, in --out DIR:
//   trajectory.txt  TUM format (timestamp tx ty tz qx qy qz qw), one line per tracked frame
//   minimaps/       mini-maps in the paper's map format, ready for wicp_align
//   session.txt     the whole session map in the same format
//   map.ply         landmarks with weights and raw metrics
//   graph.txt       the mini-map graph (docs/mapping.md), loop edges included
//   loops.txt       the accepted loops (keyframe timestamps, relative pose, inliers, fitness)
//   loop_candidates.txt  every candidate place recognition proposed and its verdict (why a loop was not closed)
//   frames.txt      one line per frame: how it was tracked, and why not (where to look when tracking is lost)
//   session/        the session folder wicp_merge reads
//   report.json     counts, timing, skipped frames, loops, ATE when ground truth exists
//   groundtruth.txt the synthetic sequence's true poses (TUM format), for wicp_evaluate
// Loops are closed by default (place recognition with the default vocabulary
// trained at build time, geometric verification, pose graph); --no-loop-closure
// turns that off.
// all built in a temporary folder beside DIR and published by one rename
// (io::AtomicFolder), so DIR never mixes runs and a failed or interrupted run
// leaves it as it was. A run that tracked no frame or mapped no landmark fails.

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <sstream>

#include <boost/program_options.hpp>

#include "interrupt.h"
#include "plotting.h"
#include "synthetic_scene_options.h"
#include "tool_support.h"
#include "weighted_icp/core/named_values.h"
#include "weighted_icp/core/statistics.h"
#include "weighted_icp/frontend/slam/frontend_choices.h"
#include "weighted_icp/io/atomic_folder.h"
#include "weighted_icp/io/camera.h"
#include "weighted_icp/io/cloud_io.h"
#include "weighted_icp/io/map_format.h"
#include "weighted_icp/io/trajectory.h"
#include "weighted_icp/io/tum_sequence.h"
#include "weighted_icp/mapping/loop_closing_slam.h"
#include "weighted_icp/mapping/loop_detector.h"
#include "weighted_icp/mapping/minimap_graph.h"
#include "weighted_icp/mapping/session.h"
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
  /// True when the ground truth is a file of the dataset already (TUM), false when only this tool knows it.
  virtual bool groundTruthOnDisk() const = 0;
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
  bool groundTruthOnDisk() const override { return true; }

 private:
  io::TumSequence sequence_;
  PinholeCamera camera_;
};

class SyntheticSource : public FrameSource {
 public:
  explicit SyntheticSource(const simulation::SyntheticRgbdOptions& options)
      : sequence_(options), tracker_camera_(sequence_.trackerCamera()) {}
  std::size_t size() const override { return sequence_.size(); }
  RgbdFrame load(std::size_t i) const override { return sequence_.frame(i).rgbd; }
  Trajectory groundTruth() const override {
    Trajectory truth;
    for (std::size_t i = 0; i < sequence_.size(); ++i)
      truth.push_back({sequence_.timestamp(i), sequence_.cameraToWorld(i)});
    return truth;
  }
  bool groundTruthOnDisk() const override { return false; }
  /// The camera the tracker is given, with the calibration error if one was asked for.
  const PinholeCamera& camera() const override { return tracker_camera_; }
  std::string describe() const override {
    const simulation::SyntheticRgbdOptions& options = sequence_.options();
    std::ostringstream out;
    out << "synthetic sequence (seed " << options.seed << ", " << options.frames_per_loop << " frames per loop"
        << (options.moving_object ? ", moving object" : "") << (options.dim_lighting ? ", dim lighting" : "")
        << (options.repeated_texture ? ", repeated texture" : "");
    if (options.room_scale != 1.0) out << ", room scaled by " << options.room_scale;
    if (options.depth_distortion != 0.0) out << ", depth distortion " << options.depth_distortion;
    if (options.focal_length_error != 0.0 || options.principal_point_error_x_px != 0.0 ||
        options.principal_point_error_y_px != 0.0)
      out << ", tracker's camera off by focal " << options.focal_length_error * 100.0 << " %, cx "
          << options.principal_point_error_x_px << " px, cy " << options.principal_point_error_y_px << " px";
    out << ")";
    return out.str();
  }

 private:
  simulation::SyntheticRgbdSequence sequence_;
  PinholeCamera tracker_camera_;
};

/// A quantile of the per-frame times; 0 when no frame was timed.
double percentile(const std::vector<double>& values, double q) { return values.empty() ? 0.0 : quantile(values, q); }

/// Counts over the processed frames, for the checks, the report and the summary line.
struct RunCounts {
  std::size_t processed = 0, unreadable = 0, tracked = 0, skipped = 0, lost = 0, clahe = 0, dynamic = 0;
  std::size_t predicted = 0;  // skipped, coasted or lost, posed by the motion model's prediction
  std::size_t coasted = 0;    // 3D-2D failed on a frame with depth: the prediction kept, tracking went on
  std::vector<double> tracking_ms;
  std::vector<double> tracking_cpu_ms;  // issue #11: the tracking thread's CPU time
  std::size_t dense = 0;                // Issue #11: frames posed by the dense odometry fallback
};

/// Feeds frames [first, frames) to `slam`, stopping early when SIGINT or SIGTERM
/// arrives (checked between frames, so a frame is never half processed).
RunCounts trackFrames(const FrameSource& source, std::size_t first, std::size_t frames,
                      mapping::LoopClosingSlam& slam) {
  RunCounts counts;
  tools::Progress progress("tracking", frames - first);
  for (std::size_t i = first; i < frames && !tools::interrupted(); ++i, ++counts.processed) {
    RgbdFrame image;
    try {
      image = source.load(i);
    } catch (const std::exception& e) {
      // A bad frame is reported and skipped; what is mapped stays.
      std::cerr << "wicp_rgbd_slam: warning: frame " << i << " skipped: " << e.what() << '\n';
      ++counts.unreadable;
      progress.step();
      continue;
    }
    const auto& record = slam.process(image);
    progress.step(frontend::toString(record.result.status) + ", " + std::to_string(record.result.inliers) + " inliers");
  }
  progress.finish();
  return counts;
}

void countResults(const frontend::RgbdSlam& slam, RunCounts& counts) {
  for (const auto& record : slam.frames()) {
    counts.tracking_ms.push_back(record.tracking_ms);
    counts.tracking_cpu_ms.push_back(record.tracking_cpu_ms);
    counts.tracked += record.result.measuredPose();
    counts.predicted += record.result.pose_predicted;
    counts.skipped += record.result.refused_by_quality_gate;
    counts.lost += record.result.status == frontend::TrackingStatus::Lost;
    counts.coasted += record.result.status == frontend::TrackingStatus::Coasted;
    counts.clahe += record.result.used_clahe;
    counts.dynamic += record.result.dynamic;
    counts.dense += record.result.status == frontend::TrackingStatus::TrackedDense;
  }
}

/// A run fails, and writes nothing, when it has nothing to align: no frame
/// tracked, or no landmark mapped (no keyframe with depth). The message says
/// what happened to the frames, so a wrong camera or depth factor shows.
void requireUsableRun(const RunCounts& counts, std::size_t frames, const LandmarkMap& session) {
  std::ostringstream frames_text;
  frames_text << " of " << frames << " frames (" << counts.unreadable << " unreadable, " << counts.skipped
              << " refused by the quality gate, " << counts.lost << " lost)";
  if (counts.tracked == 0)
    throw std::runtime_error("no frame was tracked" + frames_text.str() +
                             "; check the images, the camera and its depth_factor; nothing written");
  if (session.landmarks.empty())
    throw std::runtime_error("no landmark was mapped from " + std::to_string(counts.tracked) + " tracked" +
                             frames_text.str() + "; is there valid depth? nothing written");
}

/// The relative pose error frame to frame (evaluate_rpe.py with a fixed delta of one frame): each step's accuracy,
/// which one wrong step long ago does not dominate as it dominates the ATE; the reason instead when it cannot be had.
void addFrameToFrameRpe(const Trajectory& truth, const Trajectory& trajectory, tools::JsonObject& report) {
  try {
    const metrics::RelativePoseError rpe = metrics::computeRpe(truth, trajectory, 1.0, metrics::DeltaUnit::Frames);
    report.add("rpe_frame_translation_rmse_m", rpe.translation.rmse)
        .add("rpe_frame_rotation_rmse_deg", rpe.rotation_deg.rmse);
  } catch (const std::exception& e) {
    report.add("rpe_unavailable", std::string(e.what()));
  }
}

/// ATE against the ground truth when there is one. When it cannot be computed
/// (fewer than 3 tracked poses, no timestamps in common) the run's own outputs
/// are still valid: a warning, and the report says why instead of a number.
void addAte(const Trajectory& truth, const Trajectory& trajectory, tools::JsonObject& report,
            std::optional<metrics::AbsoluteTrajectoryError>& ate) {
  if (truth.empty()) return;
  std::string why;
  if (trajectory.size() < 3) {
    why = "only " + std::to_string(trajectory.size()) + " tracked pose(s); ATE needs 3";
  } else {
    try {
      ate = metrics::computeAte(truth, trajectory);
    } catch (const std::exception& e) {
      why = e.what();
    }
  }
  if (ate) {
    report.add("ate_rmse_m", ate->translation.rmse).add("ate_pairs", ate->pairs);
    addFrameToFrameRpe(truth, trajectory, report);
  } else {
    std::cerr << "wicp_rgbd_slam: warning: no ATE against the ground truth: " << why << '\n';
    report.add("ate_unavailable", why);
  }
}

/// Each keyframe's timestamp, by id (loops.txt and loop_candidates.txt name keyframes by their timestamps).
std::map<frontend::KeyframeId, double> keyframeTimestamps(const mapping::LoopClosingSlam& slam) {
  std::map<frontend::KeyframeId, double> timestamps;
  for (const frontend::Keyframe& keyframe : slam.slam().map().keyframes()) timestamps[keyframe.id] = keyframe.timestamp;
  return timestamps;
}

/// trajectory.png beside trajectory.txt (a missing matplotlib is a warning, not a failed run): against the ground
/// truth when there is one (the ATE's figure), else the path itself from above and from the side with the loops
/// closed, each joining its two keyframes where the corrected map puts them.
void drawTrajectory(const fs::path& png, const FrameSource& source, const Trajectory& trajectory,
                    const std::optional<metrics::AbsoluteTrajectoryError>& ate, const mapping::LoopClosingSlam& slam) {
  if (ate) {
    tools::plotTrajectory("wicp_rgbd_slam", source.groundTruth(), trajectory, ate->alignment, 0.02, png.string(),
                          source.describe());
    return;
  }
  std::map<frontend::KeyframeId, Eigen::Vector3d> positions;
  for (const frontend::Keyframe& keyframe : slam.slam().map().keyframes())
    positions[keyframe.id] = keyframe.pose_wc.translation();
  std::vector<tools::PlottedLoop> loops;
  for (const mapping::LoopConstraint& loop : slam.acceptedLoops()) {
    const auto query = positions.find(loop.query), match = positions.find(loop.match);
    if (query != positions.end() && match != positions.end()) loops.push_back({query->second, match->second, true});
  }
  tools::plotPaths("wicp_rgbd_slam", {trajectory}, {"camera path"}, loops, png.string(),
                   source.describe() + ": no ground truth, " + std::to_string(loops.size()) + " loop(s) closed");
}

/// loops.txt: one accepted loop a line, `query_timestamp match_timestamp tx ty tz qx qy qz qw inliers fitness`
/// (the query keyframe's camera in the match keyframe's, as the pose graph took it), so that a run with ground truth
/// can tell a right loop from a wrong one.
void writeLoops(const fs::path& path, const mapping::LoopClosingSlam& slam,
                const std::map<frontend::KeyframeId, double>& timestamps) {
  std::ostringstream out;
  out << "# query_timestamp match_timestamp tx ty tz qx qy qz qw inliers fitness\n" << std::setprecision(17);
  for (const mapping::LoopConstraint& loop : slam.acceptedLoops()) {
    const auto query = timestamps.find(loop.query), match = timestamps.find(loop.match);
    if (query == timestamps.end() || match == timestamps.end()) continue;  // culled by bundle adjustment since
    const Eigen::Quaterniond q(loop.query_in_match.linear());
    const Eigen::Vector3d t = loop.query_in_match.translation();
    out << query->second << ' ' << match->second << ' ' << t.x() << ' ' << t.y() << ' ' << t.z() << ' ' << q.x() << ' '
        << q.y() << ' ' << q.z() << ' ' << q.w() << ' ' << loop.inliers << ' ' << loop.fitness << '\n';
  }
  tools::writeTextFile(path.string(), out.str());
}

/// loop_candidates.txt: one candidate a line, `query_id match_id query_timestamp match_timestamp score verdict
/// reason`; the verdict is `accepted`, `pose_graph` (verified, but the pose graph's consistency test did not admit
/// it) or the verification check that refused it (LoopVerification::refused_by), the reason the rest of the line.
/// Returns the number of candidates per verdict other than accepted.
std::map<std::string, std::size_t> writeLoopCandidates(const fs::path& path, const mapping::LoopClosingSlam& slam,
                                                       const std::map<frontend::KeyframeId, double>& timestamps,
                                                       const mapping::BowLoopDetector* detector) {
  const auto timestamp = [&](frontend::KeyframeId id) {
    const auto found = timestamps.find(id);
    return found == timestamps.end() ? std::numeric_limits<double>::quiet_NaN() : found->second;
  };
  std::map<std::string, std::size_t> refusals;
  std::ostringstream out;
  out << "# query_id match_id query_timestamp match_timestamp score verdict reason\n" << std::fixed;
  const std::vector<mapping::LoopCandidateRecord> none;
  for (const mapping::LoopCandidateVerdict& v :
       mapping::candidateVerdicts(detector ? detector->candidates() : none, slam.acceptedLoops())) {
    if (v.verdict != "accepted") ++refusals[v.verdict];
    const mapping::LoopCandidateRecord& c = v.candidate;
    out << c.query << ' ' << c.match << ' ' << std::setprecision(6) << timestamp(c.query) << ' ' << timestamp(c.match)
        << ' ' << std::setprecision(3) << c.score << ' ' << v.verdict << ' ' << v.reason << '\n';
  }
  tools::writeTextFile(path.string(), out.str());
  return refusals;
}

/// frames.txt: one frame a line, `index timestamp status predicted keyframe features matches inliers dynamic
/// quality_score tracking_ms reason`: how each frame was tracked (TrackingStatus), whether its pose is the motion
/// model's prediction, and why a frame was skipped or lost.
void writeFrames(const fs::path& path, const frontend::RgbdSlam& slam) {
  std::ostringstream out;
  out << "# index timestamp status predicted keyframe features matches inliers dynamic quality_score tracking_ms "
         "reason\n";
  const auto& frames = slam.frames();
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const frontend::FrameRecord& frame = frames[i];
    const frontend::TrackingResult& r = frame.result;
    out << i << ' ' << std::fixed << std::setprecision(6) << frame.timestamp << ' ' << frontend::toString(r.status)
        << ' ' << r.pose_predicted << ' ' << r.keyframe << ' ' << r.features << ' ' << r.matches << ' ' << r.inliers
        << ' ' << r.dynamic << ' ' << std::setprecision(3) << r.quality_score << ' ' << std::setprecision(2)
        << frame.tracking_ms << ' ' << (r.reason.empty() ? "-" : r.reason) << '\n';
  }
  tools::writeTextFile(path.string(), out.str());
}

/// Writes trajectory.txt, session.txt, minimaps/, map.ply, graph.txt and session/ into `dir`.
void writeMaps(const fs::path& dir, const mapping::LoopClosingSlam& slam, const PinholeCamera& camera,
               std::size_t minimap_keyframes, const Trajectory& trajectory, const LandmarkMap& session,
               const std::vector<LandmarkMap>& minimaps) {
  fs::create_directories(dir / "minimaps");
  io::writeTrajectory(trajectory, (dir / "trajectory.txt").string());
  io::writeLandmarkMap(session, (dir / "session.txt").string());
  for (std::size_t m = 0; m < minimaps.size(); ++m) {
    std::ostringstream name;
    name << "minimap_" << std::setw(3) << std::setfill('0') << m << ".txt";
    io::writeLandmarkMap(minimaps[m], (dir / "minimaps" / name.str()).string());
  }
  io::saveLandmarkCloud(*toLandmarkCloud(session, CovarianceWeight{}), (dir / "map.ply").string());
  // The graph of the corrected map: its sequential edges carry the loop's correction.
  mapping::saveMiniMapGraph(mapping::MiniMapGraph::fromSlamMap(slam.slam().map(), minimap_keyframes),
                            (dir / "graph.txt").string());
  mapping::saveSession(mapping::captureSession(slam.slam(), camera), (dir / "session").string());
}

/// " (N candidates refused, most by CHECK: loop_candidates.txt)" for the summary line; empty when none was.
std::string refusedSummary(const std::map<std::string, std::size_t>& refusals) {
  std::size_t total = 0;
  auto most = refusals.end();
  for (auto it = refusals.begin(); it != refusals.end(); ++it) {
    total += it->second;
    if (most == refusals.end() || it->second > most->second) most = it;
  }
  if (total == 0) return "";
  return " (" + std::to_string(total) + " candidate(s) refused, most by " + most->first + ": loop_candidates.txt)";
}

/// Candidates refused, per check (loop_candidates.txt's verdicts).
tools::JsonObject refusalCounts(const std::map<std::string, std::size_t>& refusals) {
  tools::JsonObject counts;
  for (const auto& [check, count] : refusals) counts.add(check, count);
  return counts;
}

tools::JsonObject makeReport(const FrameSource& source, std::size_t frames, const mapping::LoopClosingSlam& closing,
                             const RunCounts& counts, std::size_t minimaps,
                             const std::map<std::string, std::size_t>& loop_refusals) {
  const frontend::RgbdSlam& slam = closing.slam();
  const mapping::LoopClosingStats loops = closing.loopStats();
  tools::JsonObject report;
  report.add("source", source.describe())
      .add("frames", frames)
      .add("tracked_frames", counts.tracked)
      .add("keyframes", slam.map().keyframeCount())
      .add("landmarks", slam.map().mapPointCount())
      .add("minimaps", minimaps)
      .add("median_ms_per_frame", percentile(counts.tracking_ms, 0.5))
      .add("p90_ms_per_frame", percentile(counts.tracking_ms, 0.9))
      .add("median_cpu_ms_per_frame", percentile(counts.tracking_cpu_ms, 0.5))
      .add("p90_cpu_ms_per_frame", percentile(counts.tracking_cpu_ms, 0.9))
      .add("skipped_frames", counts.skipped)
      .add("predicted_frames", counts.predicted)
      .add("coasted_frames", counts.coasted)
      .add("unreadable_frames", counts.unreadable)
      .add("lost_frames", counts.lost)
      .add("clahe_frames", counts.clahe)
      .add("dynamic_matches", counts.dynamic)
      .add("bundle_adjustments", slam.optimizationsRun())
      .add("loops_detected", loops.loops_detected)
      .add("loops_accepted", loops.loops_accepted)
      .add("pose_graph_optimisations", loops.pose_graph_optimisations)
      .add("loop_refusals", refusalCounts(loop_refusals))
      .add("global_bundle_adjustment", closing.globalBundleAdjusted())
      .add("dense_fallback_frames", counts.dense);  // Issue #11: --dense-odometry fallback
  return report;
}

/// A run stopped by SIGINT/SIGTERM after `processed` frames: nothing is
/// published, and stderr says so. Returns the exit code (130/143).
int discardInterrupted(io::AtomicFolder& folder, std::size_t processed, std::size_t frames) {
  folder.discard();
  const int signal = tools::interruptSignal();
  std::cerr << "wicp_rgbd_slam: interrupted by " << tools::signalName(signal) << " after " << processed << " of "
            << frames << " frames; no outputs written, " << folder.target().string() << " left as it was\n";
  return tools::interruptExitCode(signal);
}

/// Builds every output in the folder's temporary copy, then publishes it; an
/// exception (or a signal, checked last) leaves `--out` as it was.
int writeAndPublish(io::AtomicFolder& folder, const FrameSource& source, std::size_t frames,
                    std::size_t minimap_keyframes, const mapping::LoopClosingSlam& closing,
                    const mapping::BowLoopDetector* detector, RunCounts& counts) {
  const frontend::RgbdSlam& slam = closing.slam();
  countResults(slam, counts);
  const LandmarkMap session = slam.sessionMap();
  requireUsableRun(counts, frames, session);
  const Trajectory trajectory = slam.trajectory();
  const std::vector<LandmarkMap> minimaps = slam.miniMaps();
  writeMaps(folder.path(), closing, source.camera(), minimap_keyframes, trajectory, session, minimaps);
  const std::map<frontend::KeyframeId, double> timestamps = keyframeTimestamps(closing);
  writeLoops(folder.path() / "loops.txt", closing, timestamps);
  const std::map<std::string, std::size_t> refusals =
      writeLoopCandidates(folder.path() / "loop_candidates.txt", closing, timestamps, detector);
  writeFrames(folder.path() / "frames.txt", slam);
  tools::JsonObject report = makeReport(source, frames, closing, counts, minimaps.size(), refusals);
  std::optional<metrics::AbsoluteTrajectoryError> ate;
  const Trajectory truth = source.groundTruth();
  addAte(truth, trajectory, report, ate);
  // The synthetic sequence's truth exists nowhere else: written so that runs can be compared frame by frame.
  if (!truth.empty() && !source.groundTruthOnDisk())
    io::writeTrajectory(truth, (folder.path() / "groundtruth.txt").string());
  drawTrajectory(folder.path() / "trajectory.png", source, trajectory, ate, closing);
  tools::writeTextFile((folder.path() / "report.json").string(), report.str() + "\n");
  if (tools::interrupted()) return discardInterrupted(folder, frames, frames);  // while writing: all tracked
  folder.publish();

  std::cout << std::fixed << std::setprecision(1) << "tracked " << counts.tracked << "/" << frames << " frames, "
            << slam.map().keyframeCount() << " keyframes, " << slam.map().mapPointCount() << " landmarks, "
            << minimaps.size() << " mini-maps, " << closing.loopStats().loops_accepted << " loop(s) closed"
            << refusedSummary(refusals) << "; median " << percentile(counts.tracking_ms, 0.5) << " ms/frame (p90 "
            << percentile(counts.tracking_ms, 0.9) << "); skipped " << counts.skipped << ", coasted " << counts.coasted
            << ", lost " << counts.lost << " (" << counts.predicted << " of those posed by prediction"
            << (counts.skipped + counts.coasted + counts.lost > 0 ? "; why: frames.txt" : "") << ")\n";
  if (ate)
    std::cout << std::setprecision(2) << "ATE RMSE " << ate->translation.rmse * 100 << " cm over " << ate->pairs
              << " poses\n";
  std::cout
      << "wrote " << folder.target().string()
      << "/{trajectory.txt, session.txt, minimaps/, map.ply, graph.txt, loops.txt, loop_candidates.txt, frames.txt, "
         "session/, report.json}\n";
  return 0;
}

/// The loop detector over the vocabulary given, else the default one installed with the tools.
mapping::BowLoopDetector::Ptr makeDetector(const std::string& vocabulary_option, const PinholeCamera& camera,
                                           mapping::LoopEdgeSource edge) {
  std::string path = vocabulary_option;
  if (path.empty()) {
    path = tools::findToolDataFile("default_vocabulary.txt");
    if (path.empty())
      throw std::runtime_error(
          "no default vocabulary (default_vocabulary.txt) next to the tool or in share/weighted_icp; "
          "give --vocabulary FILE (wicp_vocabulary train makes one) or --no-loop-closure");
  }
  auto vocabulary = std::make_shared<const mapping::BinaryVocabulary>(mapping::BinaryVocabulary::load(path));
  mapping::LoopDetectorOptions options;
  options.verification.edge = edge;
  return std::make_shared<mapping::BowLoopDetector>(std::move(vocabulary), camera, std::move(options));
}

/// Refuses a matcher's own option given with another matcher, which would ignore it.
void requireOptionsOfTheMatcher(const po::variables_map& vm, frontend::MatcherKind kind) {
  using frontend::MatcherKind;
  const bool lsh = kind == MatcherKind::Lsh || kind == MatcherKind::FlannLsh;
  if (!vm["kd-backtracks"].defaulted() && kind != MatcherKind::KdTree)
    throw po::error("--kd-backtracks applies to --matcher kd-tree, not to --matcher " +
                    frontend::matcherKindName(kind));
  if (!vm["lsh-seed"].defaulted() && !lsh)
    throw po::error("--lsh-seed applies to --matcher lsh or flann, not to --matcher " +
                    frontend::matcherKindName(kind));
}

/// Everything wicp_rgbd_slam's command line sets.
struct SlamCommand {
  std::string dataset, camera_spec, out_dir, vocabulary_path;
  mapping::LoopEdgeSource loop_edge = mapping::LoopEdgeSource::Pnp;
  std::size_t max_frames = 0, first_frame = 0;
  bool overwrite = false;
  mapping::LoopClosingSlamOptions closing;
  simulation::SyntheticRgbdOptions synthetic;
  /// The choices given as words ("on", "period", "427-960", ...), by option name, each read by
  /// frontend::setFrontendChoice once parsed; the defaults are the options' own, so the help shows them.
  std::map<std::string, std::string> choices;
};

/// The words of the front end's default choices that wicp_rgbd_slam reads as text.
std::map<std::string, std::string> defaultChoiceWords(const frontend::FrontendOptions& options) {
  std::map<std::string, std::string> words;
  for (const char* key : {"describe", "gate-free-retry", "motion-timing", "keyframe-before-loss", "feature-width",
                          "pnp-thresholds", "pnp-prediction", "feature-smoothing"})
    words[key] = frontend::frontendChoiceWord(options, key);
  return words;
}

/// The usage text above the general options.
constexpr const char* kUsage =
    "wicp_rgbd_slam [--dataset DIR] [--camera fr1|fr2|fr3|FILE.yaml] [--first-frame N] [--max-frames N]\n"
    "               [--minimap-keyframes N] [--no-loop-closure | --vocabulary FILE] --out DIR [--overwrite]\n"
    "Feature-based RGB-D SLAM producing weighted landmark maps, closing loops (place recognition with\n"
    "the default vocabulary built with the tools, geometric verification, pose graph) unless\n"
    "--no-loop-closure. DIR gets trajectory.txt, session.txt, minimaps/, map.ply, graph.txt, session/\n"
    "(for wicp_merge) and report.json (docs/mapping.md). The outputs are built beside DIR\n"
    "and published in one rename: DIR holds a whole run or is left as it was.\n"
    "Exit 0: done (no ATE when the ground truth shares too few timestamps: a warning, and\n"
    "report.json says why under \"ate_unavailable\"). Exit 1, with an error line and nothing\n"
    "written: no frame tracked or no landmark mapped (black images, no depth, a wrong camera),\n"
    "or any other error. Exit 2: bad command line. Exit 130/143: stopped by SIGINT/SIGTERM,\n"
    "nothing written. Options";

/// The general options: input, range, output, matcher, gate, loop closing.
po::options_description generalOptions(SlamCommand& c) {
  frontend::FrontendOptions& frontend = c.closing.slam.frontend;
  mapping::LoopClosingOptions& loop_closing = c.closing.loop_closing;
  po::options_description description(kUsage);
  // One option per line reads as a table: not reflowed.
  // clang-format off
  description.add_options()
      ("help,h", "print this help")
      ("dataset", po::value(&c.dataset), "TUM RGB-D folder (rgb.txt, depth.txt, optional groundtruth.txt); "
                                         "default: the synthetic sequence")
      ("camera", po::value(&c.camera_spec), "fr1, fr2, fr3 or a camera YAML; default: DIR/camera.yaml, else from the folder name")
      ("first-frame", tools::rangedValue(&c.first_frame, std::size_t{0})->default_value(0),
       "start at frame N (e.g. one run of a sequence cut in two for wicp_merge)")
      ("max-frames", tools::rangedValue(&c.max_frames, std::size_t{0})->default_value(0),
       "stop before frame N, counted from the sequence's start as --first-frame is (0 = at the end): "
       "--first-frame 40 --max-frames 60 runs frames 40 to 59")
      ("minimap-keyframes", tools::rangedValue(&c.closing.slam.minimap_keyframes, std::size_t{1}, std::size_t{100000})
                                ->default_value(c.closing.slam.minimap_keyframes),
       "keyframes per mini-map (1-100000)")
      ("out", po::value(&c.out_dir)->required(), "output folder (created; published complete or not at all)")
      ("overwrite", "replace --out if it exists and is not empty")
      ("matcher", tools::namedValue(&frontend.matcher.kind, frontend::parseMatcherKind, frontend::matcherKindName),
       "flann (FLANN's LSH), lsh (our LSH: the same scheme, flat buckets, popcount), brute-force (exact, popcount) or "
       "kd-tree (our binary KD-tree, the KD-tree paper)")
      ("no-quality-gate", "do not judge frame quality (no frame is refused as a keyframe)")
      ("quality-gate", tools::namedValue(&frontend.quality.mode, frontend::parseQualityGateMode,
                                         [](frontend::QualityGateMode m) { return frontend::toString(m); }),
       "relative (sharpness against the sequence's recent frames, robust z-score), absolute (BRISQUE above 47) or paper "
       "(BRISQUE on every frame, above 47)")
      ("deterministic", "run bundle adjustment and loop closing inline instead of in their threads (reproducible)")
      ("no-loop-closure", "track and map only: no place recognition, no pose graph")
      ("loop-closing-niceness", tools::rangedValue(&loop_closing.background_niceness, 0, 19)
                                    ->default_value(loop_closing.background_niceness),
       "the loop-closing thread's nice value above tracking's (0-19): with the cores busy, tracking runs first "
       "and loops are closed a little later (0: the same priority)")
      ("vocabulary", po::value(&c.vocabulary_path), "place-recognition vocabulary (wicp_vocabulary train); "
                                                    "default: the one built with the tools")
      ("loop-edge", tools::namedValue(&c.loop_edge, mapping::parseLoopEdgeSource,
                                      [](mapping::LoopEdgeSource e) { return mapping::toString(e); }),
       "a verified loop's edge: PnP's pose (the weighted ICP checks it) or the ICP-refined pose")
      ("odometry-information", tools::namedValue(&c.closing.odometry_from_tracking, tools::parseOdometryInformation,
                                                 tools::odometryInformationName),
       "the pose graph's odometry edges: information from tracking (reprojection Hessians) or the fixed noise model")
      ("global-ba", tools::rangedValue(&c.closing.global_bundle_adjustment_iterations, 0, 1000)
                        ->default_value(c.closing.global_bundle_adjustment_iterations),
       "after the last frame and loop correction, a global bundle adjustment of every keyframe of the last segment "
       "with this many iterations (0: none; docs/mapping.md)");
  // clang-format on
  return description;
}

/// The synthetic sequence's options, in their own group so that --dataset refuses each of them (not a list of
/// names to keep in step).
po::options_description syntheticOptions(simulation::SyntheticRgbdOptions& synthetic) {
  po::options_description options("The synthetic sequence (without --dataset)");
  // clang-format off
  options.add_options()
      ("synthetic-frames", tools::rangedValue(&synthetic.frames, std::size_t{1}, std::size_t{100000})
                               ->default_value(synthetic.frames),
       "frames (1-100000)")
      ("seed", tools::rangedValue(&synthetic.seed, std::uint64_t{0})->default_value(synthetic.seed), "seed")
      ("depth-noise", tools::rangedValue(&synthetic.depth_noise_coefficient, 0.0, 1.0)
                          ->default_value(synthetic.depth_noise_coefficient),
       "depth noise sigma_z = COEFF * z^2 (0-1)")
      ("focal-error", tools::rangedValue(&synthetic.focal_length_error, -0.2, 0.2)->default_value(0.0),
       "the tracker is given fx, fy off by this fraction (an uncalibrated camera; the images are "
       "rendered with the true ones) (-0.2-0.2)")
      ("cx-error", tools::rangedValue(&synthetic.principal_point_error_x_px, -100.0, 100.0)->default_value(0.0),
       "the tracker is given cx off by this many pixels (-100-100)")
      ("cy-error", tools::rangedValue(&synthetic.principal_point_error_y_px, -80.0, 80.0)->default_value(0.0),
       "the tracker is given cy off by this many pixels (-80-80)");
  // clang-format on
  tools::addSyntheticSceneOptions(options, synthetic);
  return options;
}

/// A front-end choice read as a word by frontend::setFrontendChoice, its default the options' own.
auto choiceWord(std::map<std::string, std::string>& words, const char* key) {
  std::string& value = words.at(key);
  return po::value(&value)->default_value(value);
}

/// The papers' techniques and the choices since, in the images: features, descriptors, matching (issue #11;
/// docs/frontend_ablation.md). Each name is read by the library's parser, so the names and the error listing them
/// exist once.
void addImageOptions(po::options_description& ablation, frontend::FrontendOptions& f,
                     std::map<std::string, std::string>& words) {
  const auto name = [](auto value) { return frontend::toString(value); };
  const auto word = [&words](const char* key) { return choiceWord(words, key); };
  // clang-format off
  ablation.add_options()
      ("descriptor", tools::namedValue(&f.features.descriptor, frontend::parseDescriptorKind, frontend::descriptorKindName),
       "orb (ORB's rotated BRIEF) or modified-brief (front-end paper, Eq. 7)")
      ("kd-backtracks", tools::rangedValue(&f.matcher.kd_tree.max_backtracks, 0, 100000)
                            ->default_value(f.matcher.kd_tree.max_backtracks),
       "--matcher kd-tree: leaves visited after the first (0-100000)")
      ("lsh-seed", tools::rangedValue(&f.matcher.lsh_seed, std::uint64_t{0})->default_value(f.matcher.lsh_seed),
       "--matcher lsh or flann: seed of the LSH index's random key bits (another seed, other approximate matches: how "
       "much a result depends on them)")
      ("match-region", tools::namedValue(&f.match_region, frontend::parseMatchRegion, frontend::matchRegionName),
       "everywhere, projection (regions of interest around projected points) or homography (KD-tree paper, Eq. 8)")
      ("quality-measure", tools::namedValue(&f.quality.measure, frontend::parseQualityMeasure, name),
       "relative gate's measure: sharpness (log10 Laplacian variance, every frame) or brisque (keyframe candidates)")
      ("equalization", tools::namedValue(&f.features.equalization, frontend::parseEqualizationMethod, name),
       "a frame with too few corners: CLAHE, global histogram equalisation (the front-end paper) or none")
      ("describe", word("describe"),
       "an equalised frame's corners described in the frame as it is (original) or in the equalised image "
       "(equalized, before 2026-11-26)")
      ("feature-width", word("feature-width"),
       "MIN-MAX: frames narrower than MIN pixels are doubled, wider than MAX halved (until they are not) for "
       "finding and describing features, the keypoints kept in the frame's pixels (0: never); full: every frame at "
       "its own size")
      ("feature-smoothing", word("feature-smoothing"),
       "SIGMA: features are found, refined and described in the frame blurred by a Gaussian of SIGMA pixels (0-5) "
       "at the width they are found at: fewer corners made by JPEG and noise, better in the dark, but it cost the "
       "revisits in good light that close loops (README); off: no blur");
  // clang-format on
}

/// The papers' techniques and the choices since, in the geometry: dynamic points, dense odometry, PnP, tracking
/// losses (issue #11; docs/frontend_ablation.md).
void addGeometryOptions(po::options_description& ablation, frontend::FrontendOptions& f,
                        std::map<std::string, std::string>& words) {
  const auto name = [](auto value) { return frontend::toString(value); };
  const auto word = [&words](const char* key) { return choiceWord(words, key); };
  // clang-format off
  ablation.add_options()
      ("dynamic-distance", tools::namedValue(&f.dynamic_distance, frontend::parseDynamicDistanceKind,
                                             frontend::dynamicDistanceKindName),
       "displacement (3D), epipolar-history (front-end paper, Eq. 6, against the point's earlier values) or both")
      ("dense-odometry", tools::namedValue(&f.dense_odometry.use, frontend::parseDenseOdometryUse, name),
       "OpenCV's dense RGB-D odometry as the PnP motion prior, as the pose when 3D-2D tracking fails, both, or off")
      ("dense-odometry-kind", tools::namedValue(&f.dense_odometry.kind, frontend::parseDenseOdometryKind, name),
       "which: cv::rgbd::RgbdOdometry, ICPOdometry or RgbdICPOdometry")
      ("pnp", tools::namedValue(&f.pnp.method, frontend::parsePnpMethod, name),
       "RANSAC PnP solver: ap3p (AP3P sets, EPnP) or iterative (the paper's iterative 5-point solution)")
      ("gate-free-retry", word("gate-free-retry"),
       "on: when 3D-2D fails within both projection gates, PnP once more on the descriptor matches wherever the "
       "landmarks project; off: the 2D-2D and coasting fallbacks directly (as before 2026-11-27)")
      ("motion-timing", word("motion-timing"),
       "frame: the constant-velocity prediction repeats the last motion once a frame; period: once per frame "
       "period the timestamps count (a dropped frame: twice), better at gaps, worse in the dark (README)")
      ("keyframe-before-loss", word("keyframe-before-loss"),
       "on: when tracking is lost, the last frame 3D-2D tracked becomes the segment's last keyframe, for the next "
       "segment's bridge to find; off: as before 2026-11-27 (afternoon)")
      ("pnp-thresholds", word("pnp-thresholds"),
       "working: PnP's RANSAC threshold and Huber scale in pixels of the image features are found at (a frame "
       "halved for them: twice its own pixels); frame: in the frame's own pixels (as before 2026-11-27)")
      ("pnp-prediction", word("pnp-prediction"),
       "start: the motion model's prediction replaces RANSAC's hypothesis when it explains more matches within "
       "the RANSAC threshold; candidate: also refined on the matches it explains within twice that, kept when it "
       "ends with more inliers than RANSAC's pose")
      ("pnp-ransac-iterations", tools::rangedValue(&f.pnp.ransac_iterations, 1, 100000)
                                    ->default_value(f.pnp.ransac_iterations),
       "most RANSAC draws a frame's PnP makes; fewer when the inliers found already give 99 % confidence (1-100000)");
  // clang-format on
}

/// The papers' techniques, each an option off by default, and the choices made since (issue #11;
/// docs/frontend_ablation.md).
po::options_description ablationOptions(frontend::FrontendOptions& f, std::map<std::string, std::string>& words) {
  po::options_description ablation("The papers' techniques, for the ablation (docs/frontend_ablation.md)");
  addImageOptions(ablation, f, words);
  addGeometryOptions(ablation, f, words);
  return ablation;
}

/// Parses and checks the command line into `c`; false when only --help was asked for.
bool parseCommand(int argc, char** argv, SlamCommand& c) {
  frontend::RgbdSlamOptions& options = c.closing.slam;
  c.choices = defaultChoiceWords(options.frontend);
  po::options_description description = generalOptions(c);
  const po::options_description synthetic_options = syntheticOptions(c.synthetic);
  description.add(synthetic_options);
  description.add(ablationOptions(options.frontend, c.choices));
  po::variables_map vm;
  if (!tools::parseCommandLine(argc, argv, description, vm)) return false;
  try {
    for (const auto& [key, word] : c.choices) frontend::setFrontendChoice(options.frontend, key, word);
  } catch (const std::invalid_argument& e) {
    throw po::error(std::string("--") + e.what());
  }
  c.overwrite = vm.count("overwrite") > 0;
  options.frontend.quality_gate = !vm.count("no-quality-gate");
  options.backend.background_thread = !vm.count("deterministic");
  c.closing.loop_closing.background_thread = !vm.count("deterministic");
  c.closing.loop_closure = !vm.count("no-loop-closure");
  if (!c.closing.loop_closure && !c.vocabulary_path.empty())
    throw po::error("--vocabulary has no use with --no-loop-closure");
  tools::requireOptionsOfTheSource(vm, !c.dataset.empty(), synthetic_options);
  requireOptionsOfTheMatcher(vm, options.frontend.matcher.kind);
  return true;
}

/// The frames the command asks for: the TUM folder or the synthetic sequence.
std::unique_ptr<FrameSource> openSource(const SlamCommand& c) {
  if (c.dataset.empty()) return std::make_unique<SyntheticSource>(c.synthetic);
  return std::make_unique<TumSource>(c.dataset, io::datasetCamera(c.dataset, c.camera_spec));
}

/// The frame the run stops before (--max-frames, at most the sequence's length); refuses a --first-frame at or
/// beyond it.
std::size_t endFrame(const SlamCommand& c, const FrameSource& source) {
  const std::size_t frames = c.max_frames > 0 ? std::min(c.max_frames, source.size()) : source.size();
  if (c.first_frame >= frames)
    throw po::error("--first-frame " + std::to_string(c.first_frame) + " leaves no frame: the run stops before frame " +
                    std::to_string(frames) +
                    (c.max_frames > 0 && c.max_frames < source.size()
                         ? " (--max-frames counts from the sequence's start)"
                         : " (the sequence's length)"));
  return frames;
}

/// Tracks, maps and closes loops over the command's frames, then writes and publishes every output.
int run(const SlamCommand& c) {
  const std::unique_ptr<FrameSource> source = openSource(c);
  const std::size_t frames = endFrame(c, *source);
  // Loaded before the long run, so a bad vocabulary costs nothing.
  // Kept beside the loop closer's copy: its candidates are read for loop_candidates.txt after the run.
  mapping::BowLoopDetector::Ptr bow_detector;
  mapping::LoopDetector detector;
  if (c.closing.loop_closure) {
    bow_detector = makeDetector(c.vocabulary_path, source->camera(), c.loop_edge);
    detector = mapping::asLoopDetector(bow_detector);
  }
  // Checked and created before the long run, so a refused --out costs nothing.
  io::AtomicFolder folder = tools::openOutputFolder(c.out_dir, c.overwrite);
  std::cout << "running on " << source->describe() << ", frames " << c.first_frame << " to " << frames
            << (c.closing.loop_closure ? ", closing loops\n" : ", no loop closure\n");

  mapping::LoopClosingSlam slam(source->camera(), std::move(detector), c.closing);
  RunCounts counts = trackFrames(*source, c.first_frame, frames, slam);
  slam.finish();  // joins the bundle-adjustment and loop-closing threads, also when interrupted
  if (tools::interrupted()) return discardInterrupted(folder, counts.processed, frames - c.first_frame);
  return writeAndPublish(folder, *source, frames - c.first_frame, c.closing.slam.minimap_keyframes, slam,
                         bow_detector.get(), counts);
}

}  // namespace

int main(int argc, char** argv) {
  // First, so that a signal at any point stops the run cleanly, never killing
  // it between writing a file and publishing the folder.
  tools::installInterruptHandlers();
  return tools::runTool("wicp_rgbd_slam", [&] {
    SlamCommand command;
    if (!parseCommand(argc, argv, command)) return 0;
    return run(command);
  });
}
