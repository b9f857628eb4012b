// The mapping layer for Python: the loops a run closed (Loop) and merge_sessions(), which merges the session folders
// RgbdSlam.save_session() and wicp_rgbd_slam write, as wicp_merge does, the GIL released while it works.
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <pybind11/functional.h>
#include <pybind11/stl.h>

#include "arrays.h"
#include "bindings.h"
#include "loop_record.h"
#include "vocabulary.h"
#include "weighted_icp/mapping/session_merger.h"

namespace weighted_icp::python {

namespace {

/// One session's part of a merge, as Python reads it.
struct SessionResult {
  mapping::SessionLink link;
  std::string folder;
  Trajectory trajectory;  // empty when not merged
};

/// What merge_sessions() returns: the links, the loops between sessions, the frames and the map.
struct MergeResult {
  std::vector<SessionResult> sessions;
  std::vector<LoopRecord> loops;
  Trajectory trajectory;
  LandmarkMap map;
};

/// The sessions in their folders; FileNotFoundError for a missing folder, ValueError naming file and line for a
/// malformed record (io::MapFormatError, translated in module.cpp), RuntimeError for a missing file in a folder.
std::vector<mapping::Session> loadSessions(const std::vector<std::string>& folders) {
  py::gil_scoped_release unlocked;
  std::vector<mapping::Session> sessions;
  for (const std::string& folder : folders) sessions.push_back(mapping::loadSession(folder));
  return sessions;
}

/// The merge's loops with their keyframes' timestamps.
std::vector<LoopRecord> loopRecords(const std::vector<mapping::Session>& sessions, const mapping::SessionMerge& merge) {
  constexpr std::uint64_t stride = mapping::MiniMapGraph::kSessionIdStride;
  std::vector<std::map<frontend::KeyframeId, double>> timestamps(sessions.size());
  for (std::size_t s = 0; s < sessions.size(); ++s)
    for (const frontend::Keyframe& keyframe : sessions[s].keyframes) timestamps[s][keyframe.id] = keyframe.timestamp;
  std::vector<LoopRecord> records;
  for (std::size_t i = 0; i < merge.loops.size(); ++i) {
    const mapping::LoopConstraint& loop = merge.loops[i];
    records.push_back(toLoopRecord(loop, stride, timestamps.at(loop.query / stride).at(loop.query % stride),
                                   timestamps.at(loop.match / stride).at(loop.match % stride), merge.loop_used[i]));
  }
  return records;
}

/// progress(pass, done, total) from the merging thread, the GIL taken for it; an exception from it (or Ctrl-C)
/// stops the merge and reaches the caller.
std::function<void(const std::string&, std::size_t, std::size_t)> progressCallback(const py::object& progress) {
  if (progress.is_none()) return {};
  return [progress](const std::string& pass, std::size_t done, std::size_t total) {
    py::gil_scoped_acquire taken;
    if (PyErr_CheckSignals() != 0) throw py::error_already_set();
    progress(pass, done, total);
  };
}

MergeResult mergeSessions(const std::vector<py::object>& folders, const py::object& vocabulary,
                          std::size_t min_agreeing_loops, double max_free_space_violation, bool loops_with_link_prior,
                          const py::object& progress) {
  if (folders.empty()) throw py::value_error("sessions must name at least one session folder");
  if (min_agreeing_loops < 1) throw py::value_error("min_agreeing_loops must be >= 1");
  if (!(max_free_space_violation >= 0.0 && max_free_space_violation <= 1.0))
    throw py::value_error("max_free_space_violation must be in [0, 1]");
  std::vector<std::string> paths;
  for (const py::object& folder : folders) paths.push_back(existingPath(folder));
  const mapping::BinaryVocabulary::ConstPtr words = loadVocabulary(vocabulary);
  const std::vector<mapping::Session> sessions = loadSessions(paths);

  mapping::SessionMergeOptions options;
  options.min_agreeing_loops = min_agreeing_loops;
  options.max_free_space_violation = max_free_space_violation;
  options.loops_with_link_prior = loops_with_link_prior;
  options.progress = progressCallback(progress);
  mapping::SessionMerge merge;
  {
    py::gil_scoped_release unlocked;
    merge = mapping::mergeSessions(sessions, words, options);
  }
  MergeResult result;
  for (std::size_t s = 0; s < sessions.size(); ++s)
    result.sessions.push_back({merge.sessions[s], paths[s], merge.session_trajectories[s]});
  result.loops = loopRecords(sessions, merge);
  result.trajectory = merge.trajectory;
  result.map = merge.graph.mergedMap();
  return result;
}

void bindLoop(py::module_& m) {
  py::class_<LoopRecord>(m, "Loop",
                         "A verified loop: the query keyframe's camera in the match keyframe's (x_match = "
                         "query_in_match @ x_query), as wicp_rgbd_slam's and wicp_merge's loops.txt list them.")
      .def_readonly("query_session", &LoopRecord::query_session, "The query keyframe's session (0 within one run).")
      .def_readonly("query", &LoopRecord::query, "The query keyframe's id in its session.")
      .def_readonly("query_timestamp", &LoopRecord::query_timestamp, "The query keyframe's timestamp (s).")
      .def_readonly("match_session", &LoopRecord::match_session, "The match keyframe's session (0 within one run).")
      .def_readonly("match", &LoopRecord::match, "The match keyframe's id in its session.")
      .def_readonly("match_timestamp", &LoopRecord::match_timestamp, "The match keyframe's timestamp (s).")
      .def_property_readonly(
          "query_in_match", [](const LoopRecord& l) { return toArray(Eigen::MatrixXd(l.query_in_match)); },
          "(4, 4) float64: the query camera's pose in the match camera's frame.")
      .def_readonly("inliers", &LoopRecord::inliers, "PnP inliers.")
      .def_readonly("fitness", &LoopRecord::fitness, "The weighted ICP check's fitness (mean squared distance, m^2).")
      .def_readonly("score", &LoopRecord::score, "Place recognition's normalised score (0..1).")
      .def_readonly("used", &LoopRecord::used, "Whether the pose graph's consistency test admitted it.")
      .def("__repr__", [](const LoopRecord& l) {
        return "<Loop " + std::to_string(l.query_session) + ":" + std::to_string(l.query) + " -> " +
               std::to_string(l.match_session) + ":" + std::to_string(l.match) + ", " + std::to_string(l.inliers) +
               " inliers" + (l.used ? "" : ", not used") + ">";
      });
}

void bindMerge(py::module_& m) {
  py::class_<SessionResult>(m, "MergedSession", "One session's part of merge_sessions(), as wicp_merge's report.")
      .def_readonly("folder", &SessionResult::folder, "The session folder.")
      .def_property_readonly(
          "merged", [](const SessionResult& s) { return s.link.merged; },
          "Whether it overlaps the others and was merged; False: 'no overlap', its frames in no output.")
      .def_property_readonly(
          "linked_to", [](const SessionResult& s) { return s.link.linked_to; },
          "The merged session it was found to overlap (itself for the first).")
      .def_property_readonly(
          "loops_found", [](const SessionResult& s) { return s.link.loops_found; },
          "Verified loops against the sessions merged before it.")
      .def_property_readonly(
          "loops_agreeing", [](const SessionResult& s) { return s.link.loops_agreeing; },
          "Those agreeing on one transform.")
      .def_property_readonly(
          "loops_with_link_prior", [](const SessionResult& s) { return s.link.loops_with_link_prior; },
          "Loops added once linked, verified with the link as prior.")
      .def_property_readonly(
          "free_space_judged", [](const SessionResult& s) { return s.link.free_space_judged; },
          "Landmarks the free-space check judged (both ways).")
      .def_property_readonly(
          "free_space_violation", [](const SessionResult& s) { return s.link.free_space_violation; },
          "The fraction of them in the other session's free space (the deciding judgement).")
      .def_property_readonly(
          "free_space_rigid_violation", [](const SessionResult& s) { return s.link.free_space_rigid_violation; },
          "The fraction with the agreed transform alone.")
      .def_property_readonly(
          "free_space_optimised", [](const SessionResult& s) { return s.link.free_space_optimised; },
          "Whether the check was made again on the two sessions' maps as their joint pose graph lays them.")
      .def_property_readonly(
          "world_in_first",
          [](const SessionResult& s) { return toArray(Eigen::MatrixXd(s.link.world_in_first.matrix())); },
          "(4, 4) float64: its world frame in the first session's, after the joint optimisation.")
      .def_property_readonly(
          "trajectory",
          [](const SessionResult& s) -> py::object {
            return s.link.merged ? py::object(toTumRows(s.trajectory)) : py::none();
          },
          "Its frames in the first session's frame as (N, 8) TUM rows, or None when not merged.")
      .def("__repr__", [](const SessionResult& s) {
        return "<MergedSession " + s.folder + (s.link.merged ? ", merged" : ", no overlap") + ", " +
               std::to_string(s.link.loops_agreeing) + " agreeing loops>";
      });
  py::class_<MergeResult>(m, "SessionMerge", "What merge_sessions() found, as wicp_merge writes it.")
      .def_readonly("sessions", &MergeResult::sessions, "One MergedSession per input, in order.")
      .def_readonly("loops", &MergeResult::loops, "The agreeing loops between sessions (Loop), as loops.txt.")
      .def_property_readonly(
          "trajectory", [](const MergeResult& r) { return toTumRows(r.trajectory); },
          "(N, 8) TUM rows: every frame of every merged session in the first session's frame (original "
          "timestamps, session by session), as trajectory.txt.")
      .def_readonly("map", &MergeResult::map, "The merged landmarks as a LandmarkMap, as map.ply.")
      .def("__repr__", [](const MergeResult& r) {
        std::size_t merged = 0;
        for (const SessionResult& s : r.sessions) merged += s.link.merged ? 1 : 0;
        return "<SessionMerge " + std::to_string(merged) + " of " + std::to_string(r.sessions.size()) +
               " sessions merged, " + std::to_string(r.loops.size()) + " loops>";
      });
  m.def("merge_sessions", &mergeSessions, py::arg("sessions"), py::arg("vocabulary") = py::none(),
        py::arg("min_agreeing_loops") = mapping::SessionMergeOptions{}.min_agreeing_loops,
        py::arg("max_free_space_violation") = mapping::SessionMergeOptions{}.max_free_space_violation,
        py::arg("loops_with_link_prior") = true, py::arg("progress") = py::none(),
        "Merges session folders (RgbdSlam.save_session(), wicp_rgbd_slam's session/) into the first one's frame, "
        "as wicp_merge: place recognition, verification with no prior, min_agreeing_loops agreeing loops, the "
        "free-space check (max_free_space_violation; 1 turns it off), the other keyframes verified again with "
        "the link as prior (loops_with_link_prior=False: wicp_merge --agreeing-loops-only), one joint pose graph. "
        "A session without overlap is reported (merged False), never forced in. vocabulary: a file "
        "(wicp_vocabulary train), None for the package's default. progress(pass, done, total) after each query "
        "keyframe; an exception from it, or Ctrl-C, stops the merge. FileNotFoundError for a missing folder, "
        "ValueError naming the file and line for a malformed one. The GIL is released while it runs.");
}

}  // namespace

void bindMapping(py::module_& m) {
  bindLoop(m);
  bindMerge(m);
}

}  // namespace weighted_icp::python
