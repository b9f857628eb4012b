#pragma once
// The tracking front end: per frame, features -> matches against the local
// map -> pose (PnP + Huber LM, or 2D-2D when depth is missing) -> dynamic
// points out -> keyframe and landmark creation. The backend refines what it
// creates in its own thread.

#include <cstddef>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "weighted_icp/core/camera.h"
#include "weighted_icp/frontend/geometry/dense_odometry.h"
#include "weighted_icp/frontend/geometry/depth_noise_model.h"
#include "weighted_icp/frontend/geometry/dynamic_point_filter.h"
#include "weighted_icp/frontend/geometry/dynamic_point_history.h"
#include "weighted_icp/frontend/geometry/frame_clock.h"
#include "weighted_icp/frontend/geometry/keyframe_homography.h"
#include "weighted_icp/frontend/geometry/motion_model.h"
#include "weighted_icp/frontend/geometry/pose_estimation.h"
#include "weighted_icp/frontend/perception/descriptor_matcher.h"
#include "weighted_icp/frontend/perception/feature_extractor.h"
#include "weighted_icp/frontend/perception/image_quality_gate.h"
#include "weighted_icp/frontend/perception/roi_matcher.h"
#include "weighted_icp/frontend/slam/backend.h"
#include "weighted_icp/frontend/slam/frame.h"
#include "weighted_icp/frontend/slam/map.h"

namespace weighted_icp::frontend {

struct FrontendOptions {
  FeatureExtractorOptions features;
  /// Ratio test at 0.9, looser than the matcher's default: the projection
  /// gate and RANSAC already remove wrong matches, and on repetitive texture a
  /// strict ratio throws away good ones (measured on both TUM sequences).
  DescriptorMatcherOptions matcher = [] {
    DescriptorMatcherOptions options;
    options.ratio = 0.9f;
    return options;
  }();
  PnpOptions pnp;
  /// pnp's RANSAC threshold and Huber scale are in the working image's pixels (FeatureExtractor::workingWidth()):
  /// a frame wider than its working width has its keypoints found on a grid that much coarser, so in the frame's
  /// own pixels their errors are that much larger (a 1280x960 frame's, worked on at 640x480: twice). A frame
  /// doubled for its features keeps its own pixels' thresholds: enlarging adds no detail, its keypoints are no
  /// better located than its pixels allow. 640x480 frames are unchanged. false: in the frame's pixels, as before
  /// 2026-11-27 (pnpOptionsFor()).
  bool pnp_thresholds_in_working_pixels = true;
  DynamicPointFilterOptions dynamic_filter;
  /// Used by the backend too. sigma_z = c z^2 with c = 0.005, not the sensor's
  /// 0.0015: at a keypoint, depth also suffers from the colour/depth time
  /// offset (up to 20 ms on TUM) and registration, so it is trusted less.
  DepthNoiseModel depth_noise{0.005, 1.0};
  /// BRISQUE quality gate. It costs ~25 ms, so it judges only the frames that
  /// matter: a keyframe candidate it refuses is tracked but not mapped, and a
  /// frame that fails to track is skipped (not a tracking loss) if refused.
  bool quality_gate = true;
  ImageQualityGateOptions quality;
  double min_depth_m = 0.2;
  double max_depth_m = 5.0;
  /// A keypoint's depth counts only if its 3x3 neighbours are within this
  /// fraction of it (depth edges mix foreground and background).
  double depth_edge_tolerance = 0.03;
  std::size_t local_map_keyframes = 7;
  /// A match is kept only if the point, projected with the predicted pose,
  /// lands this close to the feature; wider before the motion is known.
  double match_gate_px = 40.0;
  double match_gate_without_motion_px = 120.0;
  /// When 3D-2D fails within both gates, PnP once more on the descriptor matches wherever the prediction puts their
  /// landmarks, RANSAC alone judging them: after frames posed without 3D-2D (2D-2D, coasted) the prediction can be
  /// so far off that the landmarks project outside even the wide gate and 3D-2D never comes back
  /// (docs/frontend_generalisation.md, "A velocity from a 2D-2D pose, and the gate-free retry on"). On since
  /// 2026-11-27: it changed no frame of the 27-row ablation and recovered real low-light runs and a fast-turning
  /// camera once 2D-2D poses no longer set the velocity.
  bool gate_free_retry = true;
  /// The constant-velocity prediction per frame period the timestamps count (a frame the sensor dropped: twice the
  /// last motion) instead of per frame. A better predictor on clean frames (fr3's doubled intervals: 1.14 -> 0.29 cm
  /// off), but it doubles a noisy velocity's error too, and tracking in the dark was worse with it; off by default
  /// (docs/frontend_generalisation.md, "A prediction per frame period, measured and left off").
  bool motion_per_period = false;
  std::size_t min_initial_points = 50;
  /// 2D-2D below this median parallax keeps the predicted translation.
  double min_parallax_deg = 1.0;
  double keyframe_translation_m = 0.08;
  double keyframe_rotation_deg = 8.0;
  /// A keyframe when fewer than this fraction of the last keyframe's tracked points are tracked.
  double keyframe_min_tracked_ratio = 0.5;
  /// When tracking is lost, the last frame 3D-2D tracked becomes its segment's last keyframe (if it is not one
  /// already): the place seen just before the loss is then in the map, for the new segment's bridge to find.
  bool keyframe_before_loss = true;
  /// New landmarks are not created this close to a feature flagged as moving.
  double dynamic_mask_radius_px = 25.0;
  /// A map point flagged as moving this many times is no longer matched
  /// (once may be depth noise; it is left out of that frame's pose either way).
  int dynamic_votes_to_exclude = 2;

  // The papers' techniques, each off by default, compared in docs/frontend_ablation.md. The descriptor is
  // features.descriptor, the KD-tree matcher matcher.kind, equalisation features.equalization, the PnP solver
  // pnp.method.
  /// Where local-map descriptors are searched: everywhere (today), or only in
  /// regions of interest around where each point is predicted to appear.
  MatchRegion match_region = MatchRegion::Everywhere;
  /// Planes of each keyframe for MatchRegion::Homography (the KD-tree paper's Eq. 8).
  PlaneFitOptions keyframe_planes;
  /// The distance that flags moving points in 3D-2D tracking.
  DynamicDistanceKind dynamic_distance = DynamicDistanceKind::Displacement;
  DynamicPointHistoryOptions dynamic_history;
  /// OpenCV's dense odometry as a motion prior and/or a fallback pose; off by default.
  DenseOdometryOptions dense_odometry;
};

enum class TrackingStatus {
  Initialized,        // a new segment (mini-map) started here
  Tracked,            // 3D-2D pose
  TrackedRelative,    // 2D-2D pose, scale from the motion model
  SkippedLowQuality,  // failed to track and refused by the image quality gate
  Lost,               // no pose; the next frame starts a new segment
  // Issue #11: dense odometry.
  TrackedDense,  // 3D-2D failed; pose from OpenCV's dense odometry against the last posed frame
  /// 3D-2D failed on a frame with depth right after a 3D-2D-tracked one: posed by the motion model's prediction
  /// (pose_predicted), the segment goes on; a 2D-2D pose there was further off than the prediction.
  Coasted
};
std::string toString(TrackingStatus status);

struct TrackingResult {
  TrackingStatus status = TrackingStatus::Lost;
  std::string reason;  // why, when Lost or Skipped
  Eigen::Isometry3d pose_wc = Eigen::Isometry3d::Identity();
  /// The keyframe the pose was tracked from, and the pose relative to it: once
  /// the backend has refined that keyframe, this frame follows it.
  KeyframeId reference_keyframe = 0;
  Eigen::Isometry3d pose_in_reference = Eigen::Isometry3d::Identity();
  bool keyframe = false;
  /// The quality gate refused this frame: skipped, or tracked but kept out of the map.
  bool refused_by_quality_gate = false;
  std::size_t features = 0;
  std::size_t matches = 0;
  std::size_t inliers = 0;
  std::size_t dynamic = 0;
  bool used_clahe = false;
  double quality_score = std::numeric_limits<double>::quiet_NaN();

  /// @brief A frame that could not be tracked (SkippedLowQuality, Coasted or Lost) while a motion was known has a pose:
  /// the constant-velocity model's prediction, so that the trajectory has every frame. Nothing of it is mapped.
  bool pose_predicted = false;

  /// @brief The frame has a pose in the trajectory: measured, or predicted (pose_predicted).
  bool hasPose() const { return measuredPose() || pose_predicted; }
  /// @brief The pose was measured from this frame's image (not predicted).
  bool measuredPose() const {
    return status == TrackingStatus::Initialized || status == TrackingStatus::Tracked ||
           status == TrackingStatus::TrackedRelative || status == TrackingStatus::TrackedDense;
  }
};

/// @brief The PnP options a frame `width` pixels wide is tracked with: options.pnp, its pixel thresholds
/// multiplied by how many of the frame's pixels one working pixel spans when options.pnp_thresholds_in_working_pixels
/// (width / FeatureExtractor::workingWidth(width), at least 1).
/// @param options  the front end's options
/// @param width    the frame's width in pixels (>= 1)
PnpOptions pnpOptionsFor(const FrontendOptions& options, int width);

/// Where the tracker stands between frames (the per-frame outcome is TrackingStatus).
/// Initializing -> Tracking: a frame with enough depth starts the first segment.
/// Tracking -> Lost: no pose, the image not refused by the quality gate; the segment ends.
/// Lost -> Tracking: a frame with enough depth starts a new segment (a new mini-map).
/// A frame that cannot start a segment leaves Initializing or Lost as it is.
enum class FrontendState {
  Initializing,  // no segment yet
  Tracking,      // a segment is being tracked and mapped
  Lost           // the last segment ended; the next frame with enough depth starts another
};
std::string toString(FrontendState state);

class Frontend {
 public:
  /// Throws if the quality gate's model files are missing (when enabled).
  Frontend(Map& map, Backend& backend, PinholeCamera camera, FrontendOptions options = {});

  /// Throws std::invalid_argument for an empty image, mismatched colour and
  /// depth sizes or a depth image that is not CV_32F. With the camera's
  /// unregistered_depth set, the depth (of the depth camera's size,
  /// PinholeCamera::depthImageSize) is first registered to the colour
  /// camera (registerDepthToColor), and the colour image must be the camera's size.
  TrackingResult track(const RgbdFrame& image);

  /// Applies a pose-graph correction posted to the map (Map::postCorrection)
  /// and moves the tracking state with it: the last pose, the motion model and
  /// the last keyframe follow the last keyframe's correction, and the local map
  /// is taken again. track() calls it first; call it after the last frame too.
  /// @return true when a correction was applied.
  bool followMapCorrection();

  FrontendState state() const { return state_; }
  /// The segment the next keyframe belongs to: 0, then one more after each loss.
  std::size_t segment() const { return segment_; }

 private:
  /// 3D-2D matches of a frame against the local map: match i pairs feature ids[i].first with point ids[i].second.
  struct LocalMatches {
    std::vector<Eigen::Vector3d> points_world;
    std::vector<Eigen::Vector2d> pixels;
    std::vector<std::pair<std::size_t, MapPointId>> ids;  // (feature, point)
    std::size_t size() const { return ids.size(); }
  };
  /// Matches flagged as moving: per match, and the pixels of those flagged.
  struct MovingPoints {
    std::vector<bool> is_dynamic;
    std::vector<Eigen::Vector2d> pixels;
  };

  /// Throws std::invalid_argument naming the frame unless it has a colour image and CV_32F depth of its size.
  static void requireImages(const RgbdFrame& image);
  /// The frame with its depth registered to the colour camera (the camera has an unregistered depth camera); throws
  /// std::invalid_argument naming the frame when the colour image is not the camera's size or the depth not the
  /// depth camera's.
  RgbdFrame withRegisteredDepth(const RgbdFrame& input) const;
  /// Features (from gray, the frame's grey image) with their undistorted pixels and depths.
  Frame makeFrame(const RgbdFrame& image, const cv::Mat& gray, bool& used_clahe);
  double depthAt(const cv::Mat& depth, const cv::Point2f& pixel) const;
  /// The one place the state changes; ends the segment when tracking is lost.
  void transitionTo(FrontendState next);
  /// 3D-2D tracking against the local map, falling back to 2D-2D.
  TrackingResult trackFrame(Frame& frame, TrackingResult result);
  /// Takes and indexes the local map again if the map changed; false when it is empty.
  bool refreshLocalMap();
  /// The descriptor matches `candidates` (localDescriptorMatches) against the local map, minus excluded moving
  /// points and those the guess projects farther than gate_px.
  LocalMatches matchLocalMap(const Frame& frame, const std::vector<cv::DMatch>& candidates,
                             const Eigen::Isometry3d& guess_wc, double gate_px) const;
  /// Flags the matches with depth whose displacement betrays a moving point, and votes against their map points.
  MovingPoints rejectMovingPoints(const Frame& frame, const LocalMatches& matched, const Eigen::Isometry3d& pose_wc);
  /// Huber refinement of the pose on the static inliers, with their depths as well as pixels.
  Eigen::Isometry3d refinePose(const Frame& frame, const LocalMatches& matched, const std::vector<int>& static_inliers,
                               const Eigen::Isometry3d& pose_wc) const;
  /// Frame periods from t0 to t1 with motion_per_period (the clock's count), else `frames`, the frames between.
  int periodsBetween(double t0, double t1, std::size_t frames) const;
  /// Records a tracked pose in the frame, the result, the motion model and the last pose.
  void acceptPose(Frame& frame, TrackingResult& result, TrackingStatus status, const Eigen::Isometry3d& pose_wc);
  /// Makes the frame a keyframe if it moved or lost enough of the tracked points and its image is good enough.
  void insertKeyframeIfNeeded(const Frame& frame, TrackingResult& result, const LocalMatches& matched,
                              const std::vector<int>& static_inliers,
                              const std::vector<Eigen::Vector2d>& dynamic_pixels);
  /// Starts a segment at the frame (its first keyframe), if it has enough features with depth.
  TrackingResult initialize(Frame& frame, TrackingResult result);
  /// 2D-2D pose against the last keyframe, scaled by the last metric motion; loses tracking if impossible.
  TrackingResult trackRelative(Frame& frame, TrackingResult result, const std::string& why_not_3d);
  // Issue #11: dense odometry.
  /// The pose guess: the dense motion from the last posed frame when it is the prior, else constant velocity.
  std::optional<Eigen::Isometry3d> predictPose();
  /// Keeps the descriptor matches `candidates` within gate_px of where `guess_wc` projects each point
  /// (matchLocalMap) and solves PnP on them; returns why it failed, empty when it did not.
  std::string solvePnpAgainstLocalMap(const Frame& frame, const std::vector<cv::DMatch>& candidates,
                                      const Eigen::Isometry3d& guess_wc, double gate_px, LocalMatches& matched,
                                      PoseEstimate& estimate) const;
  /// 3D-2D against the local map: within gate_px of the prediction, then (the motion may have changed suddenly)
  /// within the wide gate, then, with gate_free_retry, anywhere; returns why the last attempt failed, empty when one
  /// succeeded.
  std::string solveWithWiderGates(const Frame& frame, const std::vector<cv::DMatch>& candidates,
                                  const Eigen::Isometry3d& guess_wc, double gate_px, LocalMatches& matched,
                                  PoseEstimate& estimate) const;
  /// 3D-2D failed: skipped on the prediction if the quality gate refuses the image; else the dense odometry's pose
  /// when it is the fallback and registers the frame; else coasted on the prediction when canCoast; else 2D-2D.
  TrackingResult trackWithoutFeatures(Frame& frame, TrackingResult result, const std::string& why_not_3d);
  /// A frame posed by the dense odometry becomes a keyframe (its own points mapped at that pose) when it has the
  /// depth to start a map, so that 3D-2D tracking has points to match again at the next frame.
  void insertDenseKeyframe(const Frame& frame, TrackingResult& result);
  /// Pixel pairs (last keyframe, frame) of the descriptor matches between the two.
  void matchLastKeyframe(const Frame& frame, std::vector<Eigen::Vector2d>& keyframe_pixels,
                         std::vector<Eigen::Vector2d>& frame_pixels) const;
  /// No measured pose for this frame: skipped if the quality gate refuses the image (the segment goes on), else
  /// tracking is lost (the segment ends). Either way, while a motion is known, the frame gets the predicted pose.
  TrackingResult lose(TrackingResult result, const std::string& reason);
  /// Before a loss: the last 3D-2D-tracked frame, if it is not a keyframe, becomes one (options_.keyframe_before_loss).
  void keyLastTrackedFrame();
  /// While tracking, with a motion known: the constant-velocity model's pose for this frame (pose_predicted), the
  /// model advanced by it, so the next frame is predicted for its own time.
  void predictPoseOf(TrackingResult& result);
  /// Sets the pose and its expression relative to the latest keyframe.
  void setPose(TrackingResult& result, const Eigen::Isometry3d& pose_wc) const;
  /// Scores `color` with the gate; true when it is refused (never when `must_keep`, in relative mode).
  bool refusedByQualityGate(TrackingResult& result, bool must_keep = false);
  /// A frame the gate refused: SkippedLowQuality, posed by the motion model's prediction.
  TrackingResult skipLowQuality(TrackingResult result, const std::string& reason);
  /// Called for each pose measured with depth (3D-2D or dense odometry): keeps its motion from the previous frame as
  /// the metric velocity if that frame was posed with depth too; after a 2D-2D frame, restarts the motion model from
  /// the last metric velocity instead.
  void rememberMetricMotion(const Frame& frame, const Eigen::Isometry3d& pose_wc);
  /// True when a frame 3D-2D could not pose may keep the prediction instead of a 2D-2D pose: it has the depth
  /// to start a map (its matches failed, not its sensor) and the frame before it was tracked 3D-2D (once in a row:
  /// not again after a 2D-2D frame, where coasting and 2D-2D alternated for 25 frames until tracking was lost).
  bool canCoast(const Frame& frame) const;
  /// True when the camera moved or turned enough since the last keyframe, or too few of its points are tracked.
  bool needsKeyframe(const Eigen::Isometry3d& pose_wc, std::size_t tracked) const;
  // Issue #11: ROI matching and the keyframe homography (frontend_roi_matching.cpp).
  /// Descriptor matches of the frame against the local map: everywhere, or in regions of interest.
  std::vector<cv::DMatch> localDescriptorMatches(const Frame& frame, const Eigen::Isometry3d& guess_wc,
                                                 double gate_px) const;
  /// Where each local map point is expected in a frame at `guess_wc`: Eq. 8 for points on a plane of the last keyframe,
  /// else projection.
  std::vector<Eigen::Vector2d> predictLocalMapPixels(const Eigen::Isometry3d& guess_wc) const;
  /// Starts the record of the new keyframe's planes (MatchRegion::Homography).
  void recordKeyframePlanes(const Frame& frame);
  /// Records a point's pixel in the new keyframe, with the plane it lies on.
  void recordKeyframePixel(MapPointId id, const Frame& frame, std::size_t feature);
  /// Flags matches with depth whose 3D displacement disagrees with the static majority's motion
  /// (DynamicDistanceKind other than EpipolarHistory).
  std::vector<bool> flagByDisplacement(const Frame& frame, const LocalMatches& matched,
                                       const Eigen::Isometry3d& pose_wc) const;
  /// Flags matches by the Eq. 6 distance history (DynamicDistanceKind other than Displacement).
  std::vector<bool> flagByEpipolarHistory(const Frame& frame, const LocalMatches& matched,
                                          const Eigen::Isometry3d& pose_wc);

  /// Adds the frame as a keyframe: it observes the tracked points; its other features with depth become points.
  void insertKeyframe(const Frame& frame, const std::vector<std::pair<std::size_t, MapPointId>>& tracked,
                      const std::vector<Eigen::Vector2d>& dynamic_pixels);
  /// Adds the keyframe's observation of each tracked point, fused with its depth; returns the features used.
  std::vector<bool> observeTrackedPoints(KeyframeId keyframe, const Frame& frame,
                                         const std::vector<std::pair<std::size_t, MapPointId>>& tracked);
  /// A new map point for each unused feature with depth that is not near a moving one.
  void createMapPoints(KeyframeId keyframe, const Frame& frame, const std::vector<bool>& used,
                       const std::vector<Eigen::Vector2d>& dynamic_pixels);
  /// A map point from one feature's depth, observed by the keyframe.
  void createMapPoint(KeyframeId keyframe, const Frame& frame, std::size_t feature);

  Map& map_;
  Backend& backend_;
  PinholeCamera camera_;
  FrontendOptions options_;
  FeatureExtractor extractor_;
  DescriptorMatcher matcher_;
  std::optional<ImageQualityGate> quality_gate_;
  ConstantVelocityModel motion_;
  FrameClock clock_;                    // the sensor's frame period, from every frame's timestamp
  std::optional<DenseOdometry> dense_;  // Issue #11: when options_.dense_odometry.use is not Off

  std::size_t next_frame_id_ = 0;
  FrontendState state_ = FrontendState::Initializing;
  std::size_t segment_ = 0;
  std::optional<Eigen::Isometry3d> last_pose_wc_;
  /// The id of the frame last_pose_wc_ was measured on.
  std::size_t last_measured_frame_id_ = 0;
  /// And its timestamp.
  double last_measured_timestamp_ = 0.0;
  /// The id of the last frame posed by 3D-2D tracking (or starting a segment): coasting follows only such a frame.
  std::size_t last_tracked_frame_id_ = 0;
  /// The id of the last frame posed with depth (3D-2D, dense odometry, a segment's start): velocities are measured
  /// only between two such frames in a row.
  std::size_t last_metric_frame_id_ = 0;
  /// One frame's motion, between the last two consecutive frames posed with depth: what scales 2D-2D.
  std::optional<Eigen::Isometry3d> metric_velocity_;
  /// The time it spanned (seconds; 0 without timestamps): two frame periods across a dropped frame.
  double metric_velocity_seconds_ = 0.0;
  /// The last frame 3D-2D tracking posed that did not become a keyframe, with what it tracked
  /// (options_.keyframe_before_loss).
  struct UnkeyedFrame {
    Frame frame;
    std::vector<std::pair<std::size_t, MapPointId>> tracked;
    std::vector<Eigen::Vector2d> dynamic_pixels;
  };
  std::optional<UnkeyedFrame> last_unkeyed_;
  Frame last_keyframe_;
  KeyframeId last_keyframe_id_ = 0;
  std::size_t tracked_at_last_keyframe_ = 0;
  std::map<MapPointId, int> dynamic_votes_;
  LocalMap local_map_;              // what matcher_ is indexed on
  cv::Mat current_color_;           // the image being tracked, for the quality gate
  double current_timestamp_ = 0.0;  // its timestamp, for the motion model's prediction
  /// Its assessment, when the gate sees every frame.
  std::optional<QualityJudgement> frame_quality_;
  /// The gate's decision on the frame being tracked, once asked (refusedByQualityGate).
  std::optional<QualityJudgement> frame_decision_;

  // Issue #11: state of the ablation options.
  /// The last keyframe's planes (world) and, per point it observes, its pixel and plane (-1: none).
  struct KeyframePlanes {
    Eigen::Isometry3d pose_wc = Eigen::Isometry3d::Identity();
    std::vector<Plane> planes_world;
    std::vector<int> plane_of_feature;
    std::map<MapPointId, std::pair<Eigen::Vector2d, int>> points;
  };
  KeyframePlanes keyframe_planes_;
  DynamicPointHistory dynamic_history_;
};

}  // namespace weighted_icp::frontend
