// wicp_merge: merges SLAM sessions (the session/ folders wicp_rgbd_slam writes)
// into the first one's frame. Writes, in --out DIR (published by one rename):
//   trajectory.txt  every frame of every merged session, TUM format, original timestamps
//   trajectory_session_N.txt  the same, session N's frames only (unique timestamps)
//   map.ply         the merged landmarks with weights
//   graph.txt       the joint mini-map graph (sequential and merge edges)
//   loops.txt       the verified loops between sessions given to the joint pose graph (timestamps, relative pose)
//   report.json     per session: merged or not, loops found and agreeing, its frame in the first one's
//   merge.png       the merged sessions' camera paths and the loops between them, from above and from the side
//                   (matplotlib; a missing one is a warning, never a failed run)
// A session that shares no place with the others is left out and reported as
// "no overlap" (exit 0); it is never forced in.

#include <cstdint>
#include <iomanip>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>

#include <boost/program_options.hpp>

#include "plotting.h"
#include "tool_support.h"
#include "weighted_icp/io/atomic_folder.h"
#include "weighted_icp/io/cloud_io.h"
#include "weighted_icp/io/trajectory.h"
#include "weighted_icp/mapping/session_merger.h"
#include "weighted_icp/registration/landmark_point.h"

namespace po = boost::program_options;
namespace fs = std::filesystem;
using namespace weighted_icp;

namespace {

mapping::BinaryVocabulary::ConstPtr loadVocabulary(std::string path) {
  if (path.empty()) path = tools::findToolDataFile("default_vocabulary.txt");
  if (path.empty())
    throw std::runtime_error(
        "no default vocabulary (default_vocabulary.txt) next to the tool or in share/weighted_icp; give --vocabulary "
        "FILE (wicp_vocabulary train makes one)");
  return std::make_shared<const mapping::BinaryVocabulary>(mapping::BinaryVocabulary::load(path));
}

/// loops.txt: one loop between sessions a line, `query_session query_timestamp match_session match_timestamp tx ty tz
/// qx qy qz qw inliers fitness used` (the query keyframe's camera in the match keyframe's, as the joint pose graph was
/// given it; used: 1 when its consistency test admitted the loop), so that sessions with ground truth can tell a right
/// loop from a wrong one.
void writeLoops(const fs::path& path, const std::vector<mapping::Session>& sessions,
                const mapping::SessionMerge& merge) {
  constexpr std::uint64_t stride = mapping::MiniMapGraph::kSessionIdStride;
  std::vector<std::map<frontend::KeyframeId, double>> timestamps(sessions.size());
  for (std::size_t s = 0; s < sessions.size(); ++s)
    for (const frontend::Keyframe& keyframe : sessions[s].keyframes) timestamps[s][keyframe.id] = keyframe.timestamp;
  std::ostringstream out;
  out << "# query_session query_timestamp match_session match_timestamp tx ty tz qx qy qz qw inliers fitness used\n"
      << std::setprecision(17);
  for (std::size_t i = 0; i < merge.loops.size(); ++i) {
    const mapping::LoopConstraint& loop = merge.loops[i];
    const std::size_t qs = loop.query / stride, ms = loop.match / stride;
    const Eigen::Quaterniond q(loop.query_in_match.linear());
    const Eigen::Vector3d t = loop.query_in_match.translation();
    out << qs << ' ' << timestamps[qs].at(loop.query % stride) << ' ' << ms << ' '
        << timestamps[ms].at(loop.match % stride) << ' ' << t.x() << ' ' << t.y() << ' ' << t.z() << ' ' << q.x() << ' '
        << q.y() << ' ' << q.z() << ' ' << q.w() << ' ' << loop.inliers << ' ' << loop.fitness << ' '
        << (merge.loop_used[i] ? 1 : 0) << '\n';
  }
  tools::writeTextFile(path.string(), out.str());
}

tools::JsonObject makeReport(const std::vector<std::string>& folders, const mapping::SessionMerge& merge) {
  tools::JsonObject report;
  std::size_t merged = 0;
  std::string not_merged;
  report.add("sessions", folders.size());
  for (std::size_t s = 0; s < folders.size(); ++s) {
    const mapping::SessionLink& link = merge.sessions[s];
    const std::string key = "session_" + std::to_string(s);
    report.add(key + "_folder", folders[s]).add(key + "_merged", link.merged);
    if (s > 0)
      report.add(key + "_loops_found", link.loops_found)
          .add(key + "_loops_agreeing", link.loops_agreeing)
          .add(key + "_loops_with_link_prior", link.loops_with_link_prior)
          .add(key + "_free_space_judged", link.free_space_judged)
          .add(key + "_free_space_violation", link.free_space_violation)
          .add(key + "_free_space_rigid_violation", link.free_space_rigid_violation)
          .add(key + "_free_space_optimised", link.free_space_optimised);
    if (link.merged) {
      ++merged;
      report.add(key + "_linked_to", link.linked_to)
          .add(key + "_world_in_first", Eigen::MatrixXd(link.world_in_first.matrix()));
    } else {
      not_merged += (not_merged.empty() ? "" : ", ") + folders[s];
    }
  }
  report.add("merged_sessions", merged)
      .add("overlap",
           merged == folders.size() ? std::string("all sessions merged") : "no overlap: " + not_merged + " left out")
      .add("loops_accepted", merge.loops.size())
      .add("loops_used_by_pose_graph", merge.summary.loops_used)
      .add("frames", merge.trajectory.size())
      .add("minimaps", merge.graph.nodes().size());
  return report;
}

/// merge.png: each merged session's camera path in the first session's frame and the loops between sessions, their
/// keyframes placed where the joint optimisation put the frames of those timestamps.
bool plotMerge(const fs::path& png, const std::vector<std::string>& folders,
               const std::vector<mapping::Session>& sessions, const mapping::SessionMerge& merge) {
  constexpr std::uint64_t stride = mapping::MiniMapGraph::kSessionIdStride;
  std::vector<Trajectory> paths;
  std::vector<std::string> names;
  std::vector<std::map<frontend::KeyframeId, Eigen::Vector3d>> keyframe_positions(sessions.size());
  std::string left_out;
  for (std::size_t s = 0; s < sessions.size(); ++s) {
    if (!merge.sessions[s].merged) {
      left_out += (left_out.empty() ? "" : ", ") + folders[s];
      continue;
    }
    paths.push_back(merge.session_trajectories[s]);
    names.push_back("session " + std::to_string(s) + ": " + folders[s]);
    std::map<double, Eigen::Vector3d> at_time;
    for (const auto& [t, pose] : merge.session_trajectories[s]) at_time[t] = pose.translation();
    for (const frontend::Keyframe& keyframe : sessions[s].keyframes)
      if (const auto found = at_time.find(keyframe.timestamp); found != at_time.end())
        keyframe_positions[s][keyframe.id] = found->second;
  }
  std::vector<tools::PlottedLoop> loops;
  for (std::size_t i = 0; i < merge.loops.size(); ++i) {
    const auto& positions_q = keyframe_positions[merge.loops[i].query / stride];
    const auto& positions_m = keyframe_positions[merge.loops[i].match / stride];
    const auto q = positions_q.find(merge.loops[i].query % stride);
    const auto m = positions_m.find(merge.loops[i].match % stride);
    if (q != positions_q.end() && m != positions_m.end()) loops.push_back({q->second, m->second, merge.loop_used[i]});
  }
  const std::string title = "wicp_merge: " + std::to_string(paths.size()) + " of " + std::to_string(sessions.size()) +
                            " sessions merged, " + std::to_string(merge.loops.size()) + " loops between them" +
                            (left_out.empty() ? std::string() : "; no overlap: " + left_out);
  return tools::plotPaths("wicp_merge", paths, names, loops, png.string(), title);
}

/// Every output file into the (unpublished) folder `dir`; whether merge.png was drawn.
bool writeOutputs(const fs::path& dir, const std::vector<std::string>& folders,
                  const std::vector<mapping::Session>& sessions, const mapping::SessionMerge& merge) {
  io::writeTrajectory(merge.trajectory, (dir / "trajectory.txt").string());
  // Per session too: runs of one sequence that overlap in time repeat timestamps in trajectory.txt.
  for (std::size_t s = 0; s < sessions.size(); ++s)
    if (merge.sessions[s].merged)
      io::writeTrajectory(merge.session_trajectories[s],
                          (dir / ("trajectory_session_" + std::to_string(s) + ".txt")).string());
  io::saveLandmarkCloud(*toLandmarkCloud(merge.graph.mergedMap(), CovarianceWeight{}), (dir / "map.ply").string());
  mapping::saveMiniMapGraph(merge.graph, (dir / "graph.txt").string());
  writeLoops(dir / "loops.txt", sessions, merge);
  const tools::JsonObject report = makeReport(folders, merge);
  tools::writeTextFile((dir / "report.json").string(), report.str() + "\n");
  return plotMerge(dir / "merge.png", folders, sessions, merge);
}

/// Everything the command line sets.
struct MergeCommand {
  std::vector<std::string> folders;
  std::string out_dir, vocabulary_path;
  bool overwrite = false;
  mapping::SessionMergeOptions options;
};

/// Parses and checks the command line into `c`; false when only --help was asked for.
bool parseCommand(int argc, char** argv, MergeCommand& c) {
  po::options_description description(
      "wicp_merge --session A --session B [--session C ...] --out DIR [--vocabulary FILE] [--overwrite]\n"
      "Merges SLAM sessions (the session/ folders of wicp_rgbd_slam) into the first one's frame: place\n"
      "recognition between their keyframes, verification with no prior (PnP, weighted ICP), at least\n"
      "--min-loops verified loops agreeing on the transform, a free-space check, then the other keyframes\n"
      "verified again with the link as prior, one joint pose graph. DIR gets trajectory.txt\n"
      "(every frame of every merged session, TUM format), map.ply, graph.txt, loops.txt and report.json, published\n"
      "in one rename. A session without overlap is left out and the report says \"no overlap\" (exit 0).\n"
      "Exit 1: an error (a missing or corrupt session file, named with its line), nothing written.\n"
      "Exit 2: bad command line. Options");
  // clang-format off
  description.add_options()
      ("help,h", "print this help")
      ("session", po::value(&c.folders)->required(), "a session folder (repeat; at least two)")
      ("out", po::value(&c.out_dir)->required(), "output folder (created; published complete or not at all)")
      ("overwrite", "replace --out if it exists and is not empty")
      ("vocabulary", po::value(&c.vocabulary_path), "place-recognition vocabulary; default: the one built with the tools")
      ("min-loops", tools::rangedValue(&c.options.min_agreeing_loops, std::size_t{1}, std::size_t{1000})
                        ->default_value(c.options.min_agreeing_loops),
       "verified loops that must agree on a session's transform (1-1000)")
      ("max-free-space-violation", tools::rangedValue(&c.options.max_free_space_violation, 0.0, 1.0)
                                       ->default_value(c.options.max_free_space_violation),
       "largest fraction of the judged landmarks that may lie, by most of their sightings, in space the other "
       "session saw through: laid by the agreed transform or, failing that, as a pose graph of both sessions and "
       "their agreeing loops lays them (0-1; 1 turns the check off; docs/mapping.md)")
      ("agreeing-loops-only", "keep only the loops verified without prior that agree on the transform (do not "
                              "verify the other keyframes again with the link as prior)")
      ("odometry-information", tools::namedValue(&c.options.tracking_information, tools::parseOdometryInformation,
                                                 tools::odometryInformationName),
       "the joint pose graph's odometry edges within a session: information from tracking (reprojection "
       "Hessians) or the fixed noise model")
      ("minimap-keyframes", tools::rangedValue(&c.options.keyframes_per_minimap, std::size_t{1}, std::size_t{100000})
                                ->default_value(c.options.keyframes_per_minimap),
       "keyframes per mini-map of graph.txt (1-100000)");
  // clang-format on
  po::variables_map vm;
  if (!tools::parseCommandLine(argc, argv, description, vm)) return false;
  if (c.folders.size() < 2) throw po::error("give at least two --session folders");
  c.options.loops_with_link_prior = vm.count("agreeing-loops-only") == 0;
  c.overwrite = vm.count("overwrite") > 0;
  return true;
}

/// One progress line per verification pass, on stderr (SessionMergeOptions::progress).
class PassProgress {
 public:
  void operator()(const std::string& pass, std::size_t done, std::size_t total) {
    if (pass != current_pass_) {
      if (progress_) progress_->finish();
      current_pass_ = pass;
      progress_ = std::make_unique<tools::Progress>("verifying " + pass, total);
    }
    if (done > 0) progress_->step();
  }
  void finish() {
    if (progress_) progress_->finish();
  }

 private:
  std::unique_ptr<tools::Progress> progress_;
  std::string current_pass_;
};

/// One line per session after the first: merged or left out, and the loops that decided it.
void printSummary(const std::vector<std::string>& folders, const mapping::SessionMerge& merge) {
  for (std::size_t s = 1; s < folders.size(); ++s)
    std::cout << folders[s] << ": " << (merge.sessions[s].merged ? "merged" : "no overlap, left out") << " ("
              << merge.sessions[s].loops_agreeing << " agreeing of " << merge.sessions[s].loops_found
              << " verified loops, " << merge.sessions[s].loops_with_link_prior
              << " more verified with the link as prior)\n";
}

}  // namespace

int main(int argc, char** argv) {
  return tools::runTool("wicp_merge", [&] {
    MergeCommand c;
    if (!parseCommand(argc, argv, c)) return 0;
    io::AtomicFolder folder = tools::openOutputFolder(c.out_dir, c.overwrite);
    const auto vocabulary = loadVocabulary(c.vocabulary_path);
    std::vector<mapping::Session> sessions;
    for (const std::string& path : c.folders) sessions.push_back(mapping::loadSession(path));
    auto progress = std::make_shared<PassProgress>();
    c.options.progress = [progress](const std::string& pass, std::size_t done, std::size_t total) {
      (*progress)(pass, done, total);
    };
    const mapping::SessionMerge merge = mapping::mergeSessions(sessions, vocabulary, c.options);
    progress->finish();
    const bool plotted = writeOutputs(folder.path(), c.folders, sessions, merge);
    folder.publish();
    printSummary(c.folders, merge);
    std::cout << "wrote " << folder.target().string() << "/{trajectory.txt, map.ply, graph.txt, loops.txt, report.json"
              << (plotted ? ", merge.png}\n" : "}\n");
    return 0;
  });
}
