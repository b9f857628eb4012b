// The RGB-D SLAM for Python: RgbdSlam (tracking, bundle adjustment, loop closing) on a TUM folder or frame by frame,
// the GIL released while it works.
#include <cstdint>
#include <filesystem>
#include <limits>
#include <map>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <pybind11/functional.h>
#include <pybind11/stl.h>
#include <opencv2/imgproc.hpp>

#include "arrays.h"
#include "bindings.h"
#include "loop_record.h"
#include "vocabulary.h"
#include "weighted_icp/frontend/slam/frontend_choices.h"
#include "weighted_icp/frontend/slam/rgbd_slam.h"
#include "weighted_icp/io/camera.h"
#include "weighted_icp/io/tum_sequence.h"
#include "weighted_icp/mapping/loop_closing_slam.h"
#include "weighted_icp/mapping/loop_detector.h"
#include "weighted_icp/mapping/session.h"
#include "weighted_icp/registration/weight_strategies.h"

namespace weighted_icp::python {

namespace {

namespace fs = std::filesystem;

/// What track() reports for one frame.
struct TrackResult {
  std::string status;
  std::string reason;
  bool has_pose = false;
  bool pose_predicted = false;
  Eigen::Matrix4d pose = Eigen::Matrix4d::Identity();
  bool keyframe = false;
  bool refused_by_quality_gate = false;
  std::size_t features = 0, matches = 0, inliers = 0;
  double tracking_ms = 0.0;
};

TrackResult toTrackResult(const frontend::FrameRecord& record) {
  TrackResult out;
  out.status = frontend::toString(record.result.status);
  out.reason = record.result.reason;
  out.has_pose = record.result.hasPose();
  out.pose_predicted = record.result.pose_predicted;
  out.pose = record.result.pose_wc.matrix();
  out.keyframe = record.result.keyframe;
  out.refused_by_quality_gate = record.result.refused_by_quality_gate;
  out.features = record.result.features;
  out.matches = record.result.matches;
  out.inliers = record.result.inliers;
  out.tracking_ms = record.tracking_ms;
  return out;
}

PinholeCamera toCamera(const py::handle& camera) {
  if (py::isinstance<PinholeCamera>(camera)) return camera.cast<PinholeCamera>();
  if (py::isinstance<py::str>(camera)) return io::loadCamera(camera.cast<std::string>());
  throw py::value_error("camera must be a Camera or 'fr1', 'fr2', 'fr3' or a camera YAML path");
}

/// mapping::LoopClosingSlam (the SLAM wicp_rgbd_slam runs) with what Python needs around it: a lock (the GIL is
/// released while it runs, so two Python threads could otherwise enter it at once), the arrays the current frame views,
/// the ground truth of run().
class PythonSlam {
 public:
  /// @param detector  the loop detector (null without loop closure), kept to read its candidates
  PythonSlam(const PinholeCamera& camera, mapping::BowLoopDetector::Ptr detector,
             const mapping::LoopClosingSlamOptions& options)
      : camera_(camera),
        detector_(detector),
        slam_(std::make_unique<mapping::LoopClosingSlam>(
            camera, detector ? mapping::asLoopDetector(detector) : mapping::LoopDetector{}, options)) {}

  TrackResult track(const py::array& color, const py::array& depth, double timestamp, bool bgr) {
    RgbdFrame frame;
    frame.timestamp = timestamp;
    frame.color = colorImage(color, bgr);
    frame.depth = depthImage(depth);
    // The front end keeps a header of the image until the next frame: the arrays stay alive that long.
    color_owner_ = color;
    depth_owner_ = depth;
    py::gil_scoped_release unlocked;
    std::lock_guard<std::mutex> lock(mutex_);
    return toTrackResult(slam_->process(frame));
  }

  void run(const std::string& folder, std::size_t max_frames, const py::object& progress, std::size_t first_frame) {
    const io::TumSequence sequence = io::TumSequence::open(folder);
    groundtruth_ = sequence.groundTruth();
    // As wicp_rgbd_slam's --first-frame and --max-frames: both counted from the sequence's start.
    const std::size_t frames = max_frames > 0 ? std::min(max_frames, sequence.size()) : sequence.size();
    if (first_frame >= frames)
      throw py::value_error("first_frame " + std::to_string(first_frame) +
                            " leaves no frame (the run ends before frame " + std::to_string(frames) + ")");
    try {
      for (std::size_t i = first_frame; i < frames; ++i) {
        std::string status = step(sequence, i);
        if (PyErr_CheckSignals() != 0) throw py::error_already_set();  // Ctrl-C between frames
        if (!progress.is_none()) progress(i + 1 - first_frame, frames - first_frame, status);
      }
    } catch (...) {
      finish();  // the bundle-adjustment thread stops before the error reaches Python
      throw;
    }
    finish();
  }

  void finish() {
    py::gil_scoped_release unlocked;
    std::lock_guard<std::mutex> lock(mutex_);
    slam_->finish();
  }

  /// f(the tracker) under the lock.
  template <typename F>
  auto locked(F f) const {
    std::lock_guard<std::mutex> lock(mutex_);
    return f(slam_->slam());
  }

  /// f(the tracker with its loop closer) under the lock.
  template <typename F>
  auto lockedClosing(F f) const {
    std::lock_guard<std::mutex> lock(mutex_);
    return f(static_cast<const mapping::LoopClosingSlam&>(*slam_));
  }

  /// Every loop candidate's verdict, after finish() (the detector is read only when it is not running).
  std::vector<mapping::LoopCandidateVerdict> candidateVerdicts() {
    finish();
    py::gil_scoped_release unlocked;
    std::lock_guard<std::mutex> lock(mutex_);
    if (!detector_) return {};
    return mapping::candidateVerdicts(detector_->candidates(), slam_->acceptedLoops());
  }

  /// The session folder wicp_merge reads (as wicp_rgbd_slam's session/), after finish().
  void saveSession(const py::object& folder, bool overwrite) {
    const std::string path = toPath(folder);
    std::error_code error;
    if (!overwrite && fs::exists(path, error) && !fs::is_empty(path, error)) {
      PyErr_SetString(PyExc_FileExistsError, (path + ": exists and is not empty (overwrite=True replaces it)").c_str());
      throw py::error_already_set();
    }
    finish();
    py::gil_scoped_release unlocked;
    std::lock_guard<std::mutex> lock(mutex_);
    mapping::saveSession(mapping::captureSession(slam_->slam(), camera_), path, overwrite);
  }

  const PinholeCamera& camera() const { return camera_; }
  const Trajectory& groundTruth() const { return groundtruth_; }

 private:
  /// Reads and tracks frame i of the sequence; an unreadable frame is a warning and skipped, as in the tool.
  std::string step(const io::TumSequence& sequence, std::size_t i) {
    RgbdFrame frame;
    std::string error;
    {
      py::gil_scoped_release unlocked;
      try {
        frame = sequence.loadFrame(i, camera_);
      } catch (const std::runtime_error& e) {
        error = e.what();
      }
    }
    if (!error.empty()) {
      PyErr_WarnEx(PyExc_RuntimeWarning, ("frame " + std::to_string(i) + " skipped: " + error).c_str(), 1);
      return "unreadable";
    }
    py::gil_scoped_release unlocked;
    std::lock_guard<std::mutex> lock(mutex_);
    return frontend::toString(slam_->process(frame).result.status);
  }

  cv::Mat colorImage(const py::array& color, bool bgr) const {
    const bool grey = color.ndim() == 2;
    if (!color.dtype().is(py::dtype::of<std::uint8_t>()) || !(grey || (color.ndim() == 3 && color.shape(2) == 3)))
      throw py::value_error("rgb must be an (H, W, 3) or (H, W) uint8 array");
    requireCameraSize(color, "rgb");
    const py::array contiguous = py::array::ensure(color, py::array::c_style);
    cv::Mat view(static_cast<int>(color.shape(0)), static_cast<int>(color.shape(1)), grey ? CV_8UC1 : CV_8UC3,
                 const_cast<void*>(contiguous.data()));
    if (grey || bgr) return contiguous.ptr() == color.ptr() ? view : view.clone();
    cv::Mat converted;
    cv::cvtColor(view, converted, cv::COLOR_RGB2BGR);  // the front end reads OpenCV's BGR order
    return converted;
  }

  cv::Mat depthImage(const py::array& depth) const {
    const bool raw = depth.dtype().is(py::dtype::of<std::uint16_t>());
    if (depth.ndim() != 2 || !(raw || depth.dtype().is(py::dtype::of<float>())))
      throw py::value_error("depth must be an (H, W) uint16 (raw, depth_factor units) or float32 (metres) array");
    // A depth camera of its own resolution (camera.yaml's depth_width, depth_height) delivers images of its size.
    const cv::Size size = camera_.depthImageSize();
    if (depth.shape(0) != size.height || depth.shape(1) != size.width)
      throw py::value_error("depth is " + std::to_string(depth.shape(1)) + "x" + std::to_string(depth.shape(0)) +
                            " but the camera's depth images are " + std::to_string(size.width) + "x" +
                            std::to_string(size.height));
    const py::array contiguous = py::array::ensure(depth, py::array::c_style);
    cv::Mat view(size, raw ? CV_16UC1 : CV_32F, const_cast<void*>(contiguous.data()));
    if (raw) return depthFromRaw(view, camera_.depth_factor);
    return contiguous.ptr() == depth.ptr() ? view : view.clone();
  }

  void requireCameraSize(const py::array& image, const char* name) const {
    if (image.shape(0) != camera_.height || image.shape(1) != camera_.width)
      throw py::value_error(std::string(name) + " is " + std::to_string(image.shape(1)) + "x" +
                            std::to_string(image.shape(0)) + " but the camera's images are " +
                            std::to_string(camera_.width) + "x" + std::to_string(camera_.height));
  }

  PinholeCamera camera_;
  mapping::BowLoopDetector::Ptr detector_;  // shared with the loop closer's detector function
  std::unique_ptr<mapping::LoopClosingSlam> slam_;
  mutable std::mutex mutex_;
  py::object color_owner_, depth_owner_;
  Trajectory groundtruth_;
};

std::unique_ptr<PythonSlam> makeSlam(const py::object& camera, std::size_t minimap_keyframes,
                                     const std::string& matcher, bool quality_gate, bool deterministic,
                                     const std::map<std::string, std::string>& choices, bool loop_closure,
                                     const py::object& vocabulary) {
  if (minimap_keyframes < 1) throw py::value_error("minimap_keyframes must be >= 1");
  if (!loop_closure && !vocabulary.is_none()) throw py::value_error("vocabulary has no use with loop_closure=False");
  mapping::LoopClosingSlamOptions options;
  options.slam.minimap_keyframes = minimap_keyframes;
  options.slam.frontend.matcher.kind = frontend::parseMatcherKind(matcher);
  options.slam.frontend.quality_gate = quality_gate;
  for (const auto& [key, name] : choices) {
    try {
      frontend::setFrontendChoice(options.slam.frontend, key, name);
    } catch (const std::invalid_argument& e) {
      throw py::value_error(std::string("options: ") + e.what());
    }
  }
  // As wicp_rgbd_slam --deterministic: bundle adjustment and loop closing inline.
  options.slam.backend.background_thread = !deterministic;
  options.loop_closing.background_thread = !deterministic;
  options.loop_closure = loop_closure;
  const PinholeCamera cam = toCamera(camera);
  // The detector as wicp_rgbd_slam builds it (LoopDetectorOptions' defaults), loaded before any frame is tracked.
  mapping::BowLoopDetector::Ptr detector;
  if (loop_closure) detector = std::make_shared<mapping::BowLoopDetector>(loadVocabulary(vocabulary), cam);
  return std::make_unique<PythonSlam>(cam, std::move(detector), options);
}

/// RgbdSlam.landmarks: the session map's landmark positions (N, 3) and their weights by `strategy` (N,).
py::tuple landmarkCloud(const PythonSlam& slam, const std::string& strategy) {
  const WeightFunction weight = weightFunction(parseWeightStrategy(strategy));
  const LandmarkMap map = slam.locked([](const frontend::RgbdSlam& r) { return r.sessionMap(); });
  Eigen::MatrixXd positions(static_cast<Eigen::Index>(map.landmarks.size()), 3);
  for (std::size_t i = 0; i < map.landmarks.size(); ++i)
    positions.row(static_cast<Eigen::Index>(i)) = map.landmarks[i].position.transpose();
  return py::make_tuple(toArray(positions), toArray(computeWeights(map, weight)));
}

py::tuple keyframes(const PythonSlam& slam) {
  const auto all = slam.locked([](const frontend::RgbdSlam& s) { return s.map().keyframes(); });
  std::vector<std::uint64_t> ids;
  std::vector<double> stamps;
  py::array_t<double> poses({static_cast<py::ssize_t>(all.size()), py::ssize_t{4}, py::ssize_t{4}});
  auto view = poses.mutable_unchecked<3>();
  for (std::size_t i = 0; i < all.size(); ++i) {
    ids.push_back(all[i].id);
    stamps.push_back(all[i].timestamp);
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) view(static_cast<py::ssize_t>(i), r, c) = all[i].pose_wc.matrix()(r, c);
  }
  return py::make_tuple(toArray(ids), toArray(stamps), poses);
}

void bindCamera(py::module_& m) {
  py::class_<PinholeCamera>(m, "Camera",
                            "A pinhole RGB-D camera: intrinsics, distortion (k1 k2 p1 p2 k3), depth scale.")
      .def(py::init<>(), "All zero; set the fields.")
      .def_static("load", &io::loadCamera, py::arg("spec"),
                  "'fr1', 'fr2', 'fr3' (TUM's calibrations) or a camera YAML.")
      .def_static("tum", &tumCamera, py::arg("freiburg"), "The published calibration of TUM RGB-D freiburg 1, 2 or 3.")
      .def_readwrite("fx", &PinholeCamera::fx, "Focal length in x (pixels).")
      .def_readwrite("fy", &PinholeCamera::fy, "Focal length in y (pixels).")
      .def_readwrite("cx", &PinholeCamera::cx, "Principal point x (pixels).")
      .def_readwrite("cy", &PinholeCamera::cy, "Principal point y (pixels).")
      .def_readwrite("width", &PinholeCamera::width, "Image width (pixels).")
      .def_readwrite("height", &PinholeCamera::height, "Image height (pixels).")
      .def_readwrite("depth_factor", &PinholeCamera::depth_factor, "Raw depth value per metre.")
      .def_readwrite("distortion", &PinholeCamera::distortion, "k1 k2 p1 p2 k3.")
      .def_property_readonly(
          "depth_size",
          [](const PinholeCamera& c) {
            const cv::Size size = c.depthImageSize();
            return py::make_tuple(size.width, size.height);
          },
          "(width, height) of the depth images: the depth camera's own (camera.yaml's depth_width, depth_height) "
          "or the colour images'.")
      .def("__repr__", [](const PinholeCamera& c) {
        return "<Camera fx=" + std::to_string(c.fx) + " fy=" + std::to_string(c.fy) + " cx=" + std::to_string(c.cx) +
               " cy=" + std::to_string(c.cy) + " " + std::to_string(c.width) + "x" + std::to_string(c.height) + ">";
      });
}

void bindTrackResult(py::module_& m) {
  py::class_<TrackResult>(m, "TrackResult", "What track() did with one frame.")
      .def_readonly("status", &TrackResult::status, "'initialized', 'tracked', ... as wicp_rgbd_slam prints it.")
      .def_readonly("reason", &TrackResult::reason, "Why, when lost or skipped.")
      .def_readonly("has_pose", &TrackResult::has_pose, "Whether the frame got a pose (measured or predicted).")
      .def_readonly("pose_predicted", &TrackResult::pose_predicted,
                    "The frame could not be tracked (skipped or lost): its pose is the motion model's prediction.")
      .def_property_readonly(
          "pose",
          [](const TrackResult& r) -> py::object { return r.has_pose ? py::object(toArray(r.pose)) : py::none(); },
          "(4, 4) camera-to-world pose, or None.")
      .def_readonly("keyframe", &TrackResult::keyframe, "Whether it became a keyframe.")
      .def_readonly("refused_by_quality_gate", &TrackResult::refused_by_quality_gate, "Refused by the BRISQUE gate.")
      .def_readonly("features", &TrackResult::features, "Features detected.")
      .def_readonly("matches", &TrackResult::matches, "Descriptor matches.")
      .def_readonly("inliers", &TrackResult::inliers, "Pose inliers.")
      .def_readonly("tracking_ms", &TrackResult::tracking_ms, "Time inside the C++ tracker (milliseconds).")
      .def("__repr__", [](const TrackResult& r) {
        return "<TrackResult " + r.status + ", " + std::to_string(r.inliers) + " inliers>";
      });
}

/// The library's default matcher, by the name wicp_rgbd_slam's --matcher reads (one default, in the library).
std::string defaultMatcherName() { return frontend::matcherKindName(frontend::DescriptorMatcherOptions{}.kind); }

/// The constructor's docstring; its option keys are read from the front end's table, so that none is left out.
const std::string& slamInitDoc() {
  static const std::string doc = [] {
    std::string keys;
    for (const std::string& key : frontend::frontendChoiceKeys()) keys += (keys.empty() ? "" : ", ") + key;
    return "camera: a Camera, 'fr1'|'fr2'|'fr3' or a YAML path. deterministic runs bundle adjustment and loop "
           "closing inline (reproducible) instead of in their threads. loop_closure: close loops as wicp_rgbd_slam "
           "does by default (place recognition, verification, pose graph; the trajectory is the corrected one); "
           "vocabulary: its place-recognition vocabulary file, None for the package's default (FileNotFoundError "
           "when missing, ValueError naming the line when malformed). options: the front end's choices by "
           "wicp_rgbd_slam's "
           "option names and values, e.g. {'quality-measure': 'brisque', 'pnp': 'iterative'} (keys: " +
           keys + "; options win over the matcher argument); a wrong key or value raises ValueError.";
  }();
  return doc;
}

/// Each keyframe's timestamp, by id (loops and loop candidates name keyframes by their timestamps too).
std::map<frontend::KeyframeId, double> keyframeTimestamps(const frontend::RgbdSlam& slam) {
  std::map<frontend::KeyframeId, double> timestamps;
  for (const frontend::Keyframe& keyframe : slam.map().keyframes()) timestamps[keyframe.id] = keyframe.timestamp;
  return timestamps;
}

/// RgbdSlam.loops: the loops the run closed, with their keyframes' timestamps; as loops.txt, a loop one of whose
/// keyframes bundle adjustment has culled since is left out.
std::vector<LoopRecord> loopRecords(const PythonSlam& slam) {
  return slam.lockedClosing([](const mapping::LoopClosingSlam& s) {
    const std::map<frontend::KeyframeId, double> timestamps = keyframeTimestamps(s.slam());
    std::vector<LoopRecord> records;
    for (const mapping::LoopConstraint& loop : s.acceptedLoops()) {
      const auto query = timestamps.find(loop.query), match = timestamps.find(loop.match);
      if (query != timestamps.end() && match != timestamps.end())
        records.push_back(toLoopRecord(loop, 0, query->second, match->second, true));
    }
    return records;
  });
}

/// One loop candidate as Python reads it (weighted_icp.LoopCandidate).
struct CandidateRecord {
  std::uint64_t query = 0, match = 0, edge_match = 0;
  double query_timestamp = 0.0, match_timestamp = 0.0, score = 0.0;
  std::string verdict, reason;
};

/// RgbdSlam.loop_candidates(): every candidate place recognition proposed, with its verdict and timestamps.
std::vector<CandidateRecord> candidateRecords(PythonSlam& slam) {
  const std::vector<mapping::LoopCandidateVerdict> verdicts = slam.candidateVerdicts();
  const std::map<frontend::KeyframeId, double> timestamps = slam.locked(keyframeTimestamps);
  const auto timestamp = [&](frontend::KeyframeId id) {
    const auto found = timestamps.find(id);
    return found == timestamps.end() ? std::numeric_limits<double>::quiet_NaN() : found->second;
  };
  std::vector<CandidateRecord> records;
  for (const mapping::LoopCandidateVerdict& v : verdicts) {
    const mapping::LoopCandidateRecord& c = v.candidate;
    records.push_back(
        {c.query, c.match, c.edge_match, timestamp(c.query), timestamp(c.match), c.score, v.verdict, v.reason});
  }
  return records;
}

void bindLoopCandidate(py::module_& m) {
  py::class_<CandidateRecord>(m, "LoopCandidate",
                              "A keyframe place recognition proposed as a revisit, and what became of it, as "
                              "wicp_rgbd_slam's loop_candidates.txt lists it.")
      .def_readonly("query", &CandidateRecord::query, "The query keyframe's id.")
      .def_readonly("match", &CandidateRecord::match, "The proposed older keyframe's id.")
      .def_readonly("edge_match", &CandidateRecord::edge_match,
                    "The keyframe a verified loop's edge joins (the candidate's neighbour that saw the most PnP "
                    "inliers, often the candidate itself).")
      .def_readonly("query_timestamp", &CandidateRecord::query_timestamp,
                    "The query keyframe's timestamp (s; NaN for a keyframe bundle adjustment removed since).")
      .def_readonly("match_timestamp", &CandidateRecord::match_timestamp, "The candidate's timestamp (s; or NaN).")
      .def_readonly("score", &CandidateRecord::score, "Place recognition's normalised score (0..1).")
      .def_readonly("verdict", &CandidateRecord::verdict,
                    "'accepted', 'pose_graph' (verified, not admitted by the pose graph's consistency test) or the "
                    "verification check that refused it.")
      .def_readonly("reason", &CandidateRecord::reason, "Why, with the measured values.")
      .def("__repr__", [](const CandidateRecord& c) {
        return "<LoopCandidate " + std::to_string(c.query) + " -> " + std::to_string(c.match) + ": " + c.verdict + ">";
      });
}

/// RgbdSlam.loop_stats: report.json's loop counters.
std::map<std::string, std::size_t> loopStats(const PythonSlam& slam) {
  const mapping::LoopClosingStats stats =
      slam.lockedClosing([](const mapping::LoopClosingSlam& s) { return s.loopStats(); });
  return {{"loops_detected", stats.loops_detected},
          {"loops_accepted", stats.loops_accepted},
          {"pose_graph_optimisations", stats.pose_graph_optimisations}};
}

/// RgbdSlam: the SLAM fed frame by frame or over a TUM folder.
void bindSlam(py::module_& m) {
  py::class_<PythonSlam>(m, "RgbdSlam",
                         "The RGB-D SLAM (wicp_rgbd_slam's): feed frames with track(), or a TUM folder with run(); "
                         "read the trajectory (loops closed), keyframes, landmarks and loops; save the session for "
                         "merge_sessions().")
      .def(py::init(&makeSlam), py::arg("camera") = "fr1", py::arg("minimap_keyframes") = 10,
           py::arg("matcher") = defaultMatcherName(), py::arg("quality_gate") = true, py::arg("deterministic") = false,
           py::arg("options") = std::map<std::string, std::string>{}, py::arg("loop_closure") = true,
           py::arg("vocabulary") = py::none(), slamInitDoc().c_str())
      .def("track", &PythonSlam::track, py::arg("rgb"), py::arg("depth"), py::arg("timestamp"), py::arg("bgr") = false,
           "Tracks one frame: rgb (H, W, 3) uint8 in RGB order (bgr=True: OpenCV's order, not copied) or (H, W) "
           "grey; depth (H, W) uint16 raw (divided by the camera's depth_factor) or float32 metres. The GIL is "
           "released while it runs.")
      .def("run", &PythonSlam::run, py::arg("folder"), py::arg("max_frames") = 0, py::arg("progress") = py::none(),
           py::arg("first_frame") = 0,
           "Tracks the frames first_frame to max_frames - 1 of a TUM RGB-D folder, both counted from its start as "
           "wicp_rgbd_slam's --first-frame and --max-frames (max_frames 0: to the end), then finish(). "
           "progress(done, total, "
           "status) is called after each frame; an exception from it, or Ctrl-C, stops the run. Unreadable frames "
           "are skipped with a RuntimeWarning, as the tool does.")
      .def("finish", &PythonSlam::finish,
           "Waits for the pending bundle adjustment and loop closing, and applies a correction still pending.")
      .def("save_session", &PythonSlam::saveSession, py::arg("folder"), py::arg("overwrite") = false,
           "finish(), then writes the session folder merge_sessions() and wicp_merge read (wicp_rgbd_slam's "
           "session/), published by one rename; a non-empty folder is refused without overwrite=True.")
      .def_property_readonly("loops", &loopRecords,
                             "The loops closed so far (Loop), in order, as loops.txt (which leaves out a loop whose "
                             "keyframe bundle adjustment culled since).")
      .def("loop_candidates", &candidateRecords,
           "finish(), then every candidate place recognition proposed (LoopCandidate) with its verdict and reason, "
           "as loop_candidates.txt: where to look when a run closes no loop.")
      .def_property_readonly("loop_stats", &loopStats,
                             "{'loops_detected', 'loops_accepted', 'pose_graph_optimisations'}, as report.json.")
      .def_property_readonly(
          "camera", [](const PythonSlam& s) { return s.camera(); }, "The camera.")
      .def_property_readonly(
          "trajectory",
          [](const PythonSlam& s) {
            return toTumRows(s.locked([](const frontend::RgbdSlam& r) { return r.trajectory(); }));
          },
          "(N, 8) TUM rows (timestamp tx ty tz qx qy qz qw), one per frame with a pose, as loop closing corrected it.")
      .def_property_readonly(
          "ground_truth",
          [](const PythonSlam& s) -> py::object {
            return s.groundTruth().empty() ? py::none() : py::object(toTumRows(s.groundTruth()));
          },
          "The TUM folder's ground truth as (N, 8) rows after run(), else None.")
      .def_property_readonly("keyframes", &keyframes, "(ids (K,) uint64, timestamps (K,), poses (K, 4, 4)).")
      .def_property_readonly(
          "tracking_ms",
          [](const PythonSlam& s) {
            return toArray(s.locked([](const frontend::RgbdSlam& r) {
              std::vector<double> ms;
              for (const auto& f : r.frames()) ms.push_back(f.tracking_ms);
              return ms;
            }));
          },
          "(F,) float64: time of each tracked frame in the C++ tracker (milliseconds).")
      .def(
          "session_map",
          [](const PythonSlam& s) { return s.locked([](const frontend::RgbdSlam& r) { return r.sessionMap(); }); },
          "The whole map as a LandmarkMap.")
      .def(
          "mini_maps",
          [](const PythonSlam& s) { return s.locked([](const frontend::RgbdSlam& r) { return r.miniMaps(); }); },
          "The mini-maps (as wicp_rgbd_slam writes them) as LandmarkMaps.")
      .def("landmarks", &landmarkCloud, py::arg("strategy") = "covariance",
           "The landmark cloud with weights: ((N, 3) positions, (N,) weights).");
}

/// tum_frames and run_tum: a TUM folder as the front end reads it, and a run over it.
void bindTumRuns(py::module_& m) {
  m.def(
      "tum_frames",
      [](const std::string& folder) {
        const io::TumSequence sequence = io::TumSequence::open(folder);
        py::list frames;
        for (std::size_t i = 0; i < sequence.size(); ++i) {
          const io::TumFrame& frame = sequence.frame(i);
          frames.append(py::make_tuple(frame.rgb_timestamp, frame.rgb_path, frame.depth_path));
        }
        return frames;
      },
      py::arg("folder"),
      "The frames of a TUM folder as run() reads them: [(timestamp, rgb path, depth path)], rgb.txt and "
      "depth.txt associated as associate.py does (each depth image used once).");
  m.def(
      "run_tum",
      [](const std::string& folder, const py::object& camera, std::size_t max_frames, const py::object& progress,
         std::size_t minimap_keyframes, bool deterministic, const std::map<std::string, std::string>& options,
         bool loop_closure, const py::object& vocabulary, std::size_t first_frame) {
        // Python's convention: a folder or camera the caller got wrong is a ValueError, as before.
        PinholeCamera cam;
        try {
          cam = camera.is_none() ? io::datasetCamera(folder, "", "camera=") : toCamera(camera);
        } catch (const std::runtime_error& e) {
          throw py::value_error(e.what());
        }
        auto slam = makeSlam(py::cast(cam), minimap_keyframes, defaultMatcherName(), true, deterministic, options,
                             loop_closure, vocabulary);
        slam->run(folder, max_frames, progress, first_frame);
        return slam;
      },
      py::arg("folder"), py::arg("camera") = py::none(), py::arg("max_frames") = 0, py::arg("progress") = py::none(),
      py::arg("minimap_keyframes") = 10, py::arg("deterministic") = false,
      py::arg("options") = std::map<std::string, std::string>{}, py::arg("loop_closure") = true,
      py::arg("vocabulary") = py::none(), py::arg("first_frame") = 0,
      "A new RgbdSlam run over a TUM folder (first_frame, max_frames as run()'s); the camera, when not given, the "
      "folder's camera.yaml, else from its name "
      "(fr1 ...); options, loop_closure and vocabulary as RgbdSlam's.");
}

}  // namespace

void bindFrontend(py::module_& m) {
  bindCamera(m);
  bindTrackResult(m);
  bindLoopCandidate(m);
  bindSlam(m);
  bindTumRuns(m);
}

}  // namespace weighted_icp::python
