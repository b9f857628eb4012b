#include "weighted_icp/frontend/slam/frontend.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "weighted_icp/frontend/perception/depth_registration.h"

namespace weighted_icp::frontend {

std::string toString(TrackingStatus status) {
  switch (status) {
    case TrackingStatus::Initialized: return "initialized";
    case TrackingStatus::Tracked: return "tracked";
    case TrackingStatus::TrackedRelative: return "tracked-2d2d";
    case TrackingStatus::SkippedLowQuality: return "skipped-low-quality";
    case TrackingStatus::Lost: return "lost";
    case TrackingStatus::TrackedDense: return "tracked-dense";
    case TrackingStatus::Coasted: return "coasted";
  }
  return "unknown";
}

std::string toString(FrontendState state) {
  switch (state) {
    case FrontendState::Initializing: return "initializing";
    case FrontendState::Tracking: return "tracking";
    case FrontendState::Lost: return "lost";
  }
  return "unknown";
}

namespace {

double rotationAngleDeg(const Eigen::Isometry3d& motion) {
  return Eigen::AngleAxisd(motion.linear()).angle() * 180.0 / M_PI;
}

/// World position and covariance of a feature measured with depth from `pose_wc`.
FusedPoint measuredPoint(const PinholeCamera& camera, const DepthNoiseModel& noise, const Eigen::Isometry3d& pose_wc,
                         const Eigen::Vector2d& pixel, double depth) {
  const Eigen::Matrix3d rotation = pose_wc.linear();
  return {pose_wc * camera.backProject(pixel.x(), pixel.y(), depth),
          rotation * pointCovarianceCamera(camera, pixel.x(), pixel.y(), depth, noise) * rotation.transpose()};
}

}  // namespace

PnpOptions pnpOptionsFor(const FrontendOptions& options, int width) {
  PnpOptions pnp = options.pnp;
  if (!options.pnp_thresholds_in_working_pixels) return pnp;
  const double scale =
      std::max(1.0, static_cast<double>(width) / FeatureExtractor(options.features).workingWidth(width));
  pnp.ransac_reprojection_px *= scale;
  pnp.huber_px *= scale;
  return pnp;
}

Frontend::Frontend(Map& map, Backend& backend, PinholeCamera camera, FrontendOptions options)
    : map_(map),
      backend_(backend),
      camera_(camera),
      options_(options),
      extractor_(options.features),
      matcher_(options.matcher),
      dynamic_history_(options.dynamic_history) {
  options_.pnp = pnpOptionsFor(options_, camera_.width);
  if (options_.quality_gate) quality_gate_.emplace(options_.quality);
  if (options_.dense_odometry.use != DenseOdometryUse::Off) dense_.emplace(camera_, options_.dense_odometry.kind);
}

double Frontend::depthAt(const cv::Mat& depth, const cv::Point2f& pixel) const {
  // Depth is registered to the raw (distorted) colour image. Corners often lie
  // on depth edges, where the sensor mixes foreground and background: a depth
  // is trusted only if its 3x3 neighbourhood agrees with it.
  const int u = static_cast<int>(std::lround(pixel.x));
  const int v = static_cast<int>(std::lround(pixel.y));
  if (u < 1 || v < 1 || u >= depth.cols - 1 || v >= depth.rows - 1) return 0.0;
  const double z = depth.at<float>(v, u);
  if (!std::isfinite(z) || z < options_.min_depth_m || z > options_.max_depth_m) return 0.0;
  const double tolerance = options_.depth_edge_tolerance * z;
  for (int dv = -1; dv <= 1; ++dv)
    for (int du = -1; du <= 1; ++du) {
      const double neighbour = depth.at<float>(v + dv, u + du);
      if (!std::isfinite(neighbour) || std::abs(neighbour - z) > tolerance) return 0.0;
    }
  return z;
}

void Frontend::requireImages(const RgbdFrame& image) {
  if (image.color.empty()) throw std::invalid_argument("frame at " + std::to_string(image.timestamp) + ": empty image");
  if (image.depth.type() != CV_32F || image.depth.size() != image.color.size())
    throw std::invalid_argument("frame at " + std::to_string(image.timestamp) +
                                ": depth must be CV_32F metres of the colour image's size");
}

RgbdFrame Frontend::withRegisteredDepth(const RgbdFrame& input) const {
  const cv::Size depth_size = camera_.depthImageSize();
  const auto size = [](int width, int height) { return std::to_string(width) + "x" + std::to_string(height); };
  if (input.color.cols != camera_.width || input.color.rows != camera_.height)
    throw std::invalid_argument("frame at " + std::to_string(input.timestamp) + ": the colour image is " +
                                size(input.color.cols, input.color.rows) + ", the camera's " +
                                size(camera_.width, camera_.height));
  if (input.depth.type() != CV_32F || input.depth.size() != depth_size)
    throw std::invalid_argument(
        "frame at " + std::to_string(input.timestamp) + ": depth must be CV_32F metres of the depth camera's size " +
        size(depth_size.width, depth_size.height) + ", found " + size(input.depth.cols, input.depth.rows) +
        (input.depth.type() == CV_32F ? "" : " not of CV_32F"));
  RgbdFrame image = input;
  image.depth = registerDepthToColor(input.depth, camera_);
  return image;
}

Frame Frontend::makeFrame(const RgbdFrame& image, const cv::Mat& gray, bool& used_clahe) {
  Frame frame;
  frame.id = next_frame_id_++;
  frame.timestamp = image.timestamp;
  ExtractedFeatures features = extractor_.extract(gray);
  used_clahe = features.used_clahe;
  frame.keypoints = std::move(features.keypoints);
  frame.descriptors = features.descriptors;

  std::vector<cv::Point2f> detected, undistorted;
  for (const auto& keypoint : frame.keypoints) detected.push_back(keypoint.pt);
  if (camera_.hasDistortion() && !detected.empty())
    cv::undistortPoints(detected, undistorted, camera_.cameraMatrix(), camera_.distortionCoefficients(), cv::noArray(),
                        camera_.cameraMatrix());
  else
    undistorted = detected;
  frame.pixels.reserve(detected.size());
  frame.depths.reserve(detected.size());
  for (std::size_t i = 0; i < detected.size(); ++i) {
    frame.pixels.emplace_back(undistorted[i].x, undistorted[i].y);
    frame.depths.push_back(depthAt(image.depth, detected[i]));
  }
  return frame;
}

TrackingResult Frontend::track(const RgbdFrame& input) {
  // A sensor whose depth camera is not its colour camera: its depth moved into the colour pixels first.
  const RgbdFrame image = camera_.unregistered_depth ? withRegisteredDepth(input) : input;
  TrackingResult result;
  requireImages(image);
  const cv::Mat gray = image.gray();  // once a frame: the features and the dense odometry
  Frame frame = makeFrame(image, gray, result.used_clahe);
  result.features = frame.size();
  current_color_ = image.color;
  current_timestamp_ = frame.timestamp;
  clock_.tick(frame.timestamp);
  if (dense_) dense_->setCurrent(image, gray);
  followMapCorrection();
  frame_quality_.reset();
  frame_decision_.reset();
  if (quality_gate_ && quality_gate_->assessesEveryFrame()) {
    // Cheap measures (and the paper's gate) see every frame: the history is the whole sequence.
    frame_quality_ = quality_gate_->assess(current_color_);
    result.quality_score = frame_quality_->score;
    if (options_.quality.mode == QualityGateMode::PaperEveryFrame && frame_quality_->refused) {
      // The front-end paper's gate: a bad frame is dropped before tracking.
      result.refused_by_quality_gate = true;
      result.status = TrackingStatus::SkippedLowQuality;
      result.reason = "BRISQUE " + std::to_string(frame_quality_->score);
      predictPoseOf(result);
      return result;
    }
  }
  if (state_ != FrontendState::Tracking) return initialize(frame, result);
  return trackFrame(frame, result);
}

bool Frontend::followMapCorrection() {
  const auto delta_wc = map_.applyPendingCorrection(last_keyframe_id_);
  if (!delta_wc) return false;
  // The tracker's state is where its last keyframe was: it moves as that keyframe did.
  if (last_pose_wc_) last_pose_wc_ = *delta_wc * *last_pose_wc_;
  motion_.applyCorrection(*delta_wc);
  last_keyframe_.pose_wc = *delta_wc * last_keyframe_.pose_wc;
  if (last_unkeyed_) last_unkeyed_->frame.pose_wc = *delta_wc * last_unkeyed_->frame.pose_wc;
  local_map_ = LocalMap{};  // the revision changed too; the points moved
  return true;
}

void Frontend::transitionTo(FrontendState next) {
  if (next == FrontendState::Lost) {
    // Everything mapped so far stays; the next keyframe belongs to a new segment.
    if (state_ == FrontendState::Tracking) ++segment_;
    motion_.reset();
  } else if (next == FrontendState::Tracking && state_ != FrontendState::Tracking) {
    // A segment starts afresh: no motion carries over from before the loss.
    motion_.reset();
    metric_velocity_.reset();
  }
  state_ = next;
}

bool Frontend::refusedByQualityGate(TrackingResult& result, bool must_keep) {
  // The paper's mode dropped bad frames in track() already.
  if (!quality_gate_ || options_.quality.mode == QualityGateMode::PaperEveryFrame) return false;
  // Asked once a frame: a second question (2D-2D failed after the gate kept the frame) gets the same answer, and
  // the gate counts one refusal in a row, not two.
  if (!frame_decision_) {
    QualityJudgement judgement = frame_quality_ ? *frame_quality_ : quality_gate_->assess(current_color_);
    quality_gate_->decide(judgement, must_keep);
    frame_decision_ = judgement;
  }
  result.quality_score = frame_decision_->score;
  result.refused_by_quality_gate = frame_decision_->refused;
  return result.refused_by_quality_gate;
}

TrackingResult Frontend::skipLowQuality(TrackingResult result, const std::string& reason) {
  // A bad image (blur, noise) is not a lost track: skip it on the motion model's prediction, keep the motion.
  predictPoseOf(result);
  result.status = TrackingStatus::SkippedLowQuality;
  result.reason = reason + "; quality score " + std::to_string(result.quality_score);
  return result;
}

TrackingResult Frontend::trackFrame(Frame& frame, TrackingResult result) {
  const auto predicted = predictPose();
  const Eigen::Isometry3d guess_wc = predicted ? *predicted : *last_pose_wc_;
  const double gate_px = predicted ? options_.match_gate_px : options_.match_gate_without_motion_px;
  if (!refreshLocalMap()) return lose(result, "the local map is empty");

  const std::vector<cv::DMatch> candidates = localDescriptorMatches(frame, guess_wc, gate_px);
  LocalMatches matched;
  PoseEstimate estimate;
  const std::string failure = solveWithWiderGates(frame, candidates, guess_wc, gate_px, matched, estimate);
  result.matches = matched.size();
  if (!failure.empty()) return trackWithoutFeatures(frame, result, failure);

  const MovingPoints moving = rejectMovingPoints(frame, matched, estimate.pose_wc);
  std::vector<int> static_inliers;
  for (const int m : estimate.inliers)
    if (!moving.is_dynamic[m]) static_inliers.push_back(m);
  result.dynamic = moving.pixels.size();
  if (static_inliers.size() < static_cast<std::size_t>(options_.pnp.min_inliers))
    return trackWithoutFeatures(frame, result, std::to_string(static_inliers.size()) + " static inliers");

  const Eigen::Isometry3d pose_wc = refinePose(frame, matched, static_inliers, estimate.pose_wc);
  rememberMetricMotion(frame, pose_wc);
  acceptPose(frame, result, TrackingStatus::Tracked, pose_wc);
  last_tracked_frame_id_ = frame.id;
  result.inliers = static_inliers.size();
  insertKeyframeIfNeeded(frame, result, matched, static_inliers, moving.pixels);
  return result;
}

std::string Frontend::solvePnpAgainstLocalMap(const Frame& frame, const std::vector<cv::DMatch>& candidates,
                                              const Eigen::Isometry3d& guess_wc, double gate_px, LocalMatches& matched,
                                              PoseEstimate& estimate) const {
  matched = matchLocalMap(frame, candidates, guess_wc, gate_px);
  if (matched.size() < static_cast<std::size_t>(options_.pnp.min_inliers))
    return std::to_string(matched.size()) + " 3D-2D matches";
  estimate = estimatePosePnp(matched.points_world, matched.pixels, camera_, guess_wc, options_.pnp);
  return estimate.ok ? std::string() : "PnP failed: " + estimate.failure;
}

std::string Frontend::solveWithWiderGates(const Frame& frame, const std::vector<cv::DMatch>& candidates,
                                          const Eigen::Isometry3d& guess_wc, double gate_px, LocalMatches& matched,
                                          PoseEstimate& estimate) const {
  std::string failure = solvePnpAgainstLocalMap(frame, candidates, guess_wc, gate_px, matched, estimate);
  // Each wider attempt replaces the result only when it succeeds. Only regions of interest depend on the gate; a
  // search everywhere is not repeated.
  const bool everywhere = options_.match_region == MatchRegion::Everywhere;
  const auto attempt = [&](double wider_px, const std::string& name) {
    const std::vector<cv::DMatch> searched_again =
        everywhere ? std::vector<cv::DMatch>{} : localDescriptorMatches(frame, guess_wc, wider_px);
    LocalMatches wider;
    PoseEstimate wider_estimate;
    const std::string wider_failure = solvePnpAgainstLocalMap(frame, everywhere ? candidates : searched_again, guess_wc,
                                                              wider_px, wider, wider_estimate);
    if (wider_failure.empty()) {
      matched = std::move(wider);
      estimate = std::move(wider_estimate);
      failure.clear();
    } else {
      failure += "; " + name + ": " + wider_failure;
    }
  };
  // The prediction may be far off (the motion changed suddenly): the gate of a frame without known motion.
  const double wide_px = options_.match_gate_without_motion_px;
  if (!failure.empty() && gate_px < wide_px)
    attempt(wide_px, "within " + std::to_string(static_cast<int>(wide_px)) + " px");
  // Or the prediction itself is off after frames posed without 3D-2D: wherever the landmarks project.
  constexpr double kAnywherePx = 1e5;  // beyond any image, finite for the regions of interest's grid
  if (!failure.empty() && options_.gate_free_retry) attempt(kAnywherePx, "anywhere");
  return failure;
}

bool Frontend::refreshLocalMap() {
  // Taken and indexed again only when the map changed (a keyframe, a BA).
  if (map_.revision() != local_map_.revision || local_map_.ids.empty()) {
    local_map_ = map_.localMap(options_.local_map_keyframes);
    // Regions of interest search the descriptors directly: no index to build.
    if (!local_map_.ids.empty() && options_.match_region == MatchRegion::Everywhere)
      matcher_.setReference(local_map_.descriptors);
  }
  return !local_map_.ids.empty();
}

Frontend::LocalMatches Frontend::matchLocalMap(const Frame& frame, const std::vector<cv::DMatch>& candidates,
                                               const Eigen::Isometry3d& guess_wc, double gate_px) const {
  const LocalMap& local = local_map_;
  const Eigen::Isometry3d guess_cw = guess_wc.inverse();
  LocalMatches matched;
  for (const cv::DMatch& match : candidates) {
    const MapPointId id = local.ids[match.trainIdx];
    const auto votes = dynamic_votes_.find(id);
    if (votes != dynamic_votes_.end() && votes->second >= options_.dynamic_votes_to_exclude) continue;
    const Eigen::Vector3d point_camera = guess_cw * local.positions[match.trainIdx];
    if (point_camera.z() <= 0.0) continue;
    if ((camera_.project(point_camera) - frame.pixels[match.queryIdx]).norm() > gate_px) continue;
    matched.points_world.push_back(local.positions[match.trainIdx]);
    matched.pixels.push_back(frame.pixels[match.queryIdx]);
    matched.ids.emplace_back(static_cast<std::size_t>(match.queryIdx), id);
  }
  return matched;
}

std::vector<bool> Frontend::flagByDisplacement(const Frame& frame, const LocalMatches& matched,
                                               const Eigen::Isometry3d& pose_wc) const {
  // Each match with depth is checked against the motion of the static majority.
  std::vector<Eigen::Vector3d> with_depth_world, with_depth_measured;
  std::vector<std::size_t> with_depth_match;
  for (std::size_t m = 0; m < matched.size(); ++m) {
    const std::size_t feature = matched.ids[m].first;
    if (!frame.hasDepth(feature)) continue;
    with_depth_world.push_back(matched.points_world[m]);
    with_depth_measured.push_back(
        camera_.backProject(frame.pixels[feature].x(), frame.pixels[feature].y(), frame.depths[feature]));
    with_depth_match.push_back(m);
  }
  const std::vector<bool> moving = flagDynamicByDisplacement(with_depth_world, with_depth_measured, pose_wc,
                                                             options_.depth_noise, options_.dynamic_filter);
  std::vector<bool> is_dynamic(matched.size(), false);
  for (std::size_t k = 0; k < moving.size(); ++k)
    if (moving[k]) is_dynamic[with_depth_match[k]] = true;
  return is_dynamic;
}

Frontend::MovingPoints Frontend::rejectMovingPoints(const Frame& frame, const LocalMatches& matched,
                                                    const Eigen::Isometry3d& pose_wc) {
  // Flagged matches leave the pose and never become landmarks; each distance is computed only when selected.
  std::vector<bool> is_dynamic(matched.size(), false);
  if (options_.dynamic_distance != DynamicDistanceKind::EpipolarHistory)
    is_dynamic = flagByDisplacement(frame, matched, pose_wc);
  if (options_.dynamic_distance != DynamicDistanceKind::Displacement) {
    const std::vector<bool> by_history = flagByEpipolarHistory(frame, matched, pose_wc);
    for (std::size_t m = 0; m < matched.size(); ++m) is_dynamic[m] = is_dynamic[m] || by_history[m];
  }
  MovingPoints flagged;
  flagged.is_dynamic.assign(matched.size(), false);
  for (std::size_t m = 0; m < matched.size(); ++m) {
    if (!is_dynamic[m]) continue;
    flagged.is_dynamic[m] = true;
    ++dynamic_votes_[matched.ids[m].second];
    flagged.pixels.push_back(matched.pixels[m]);
  }
  return flagged;
}

Eigen::Isometry3d Frontend::refinePose(const Frame& frame, const LocalMatches& matched,
                                       const std::vector<int>& static_inliers, const Eigen::Isometry3d& pose_wc) const {
  std::vector<double> match_depths(matched.size());
  for (std::size_t m = 0; m < matched.size(); ++m) match_depths[m] = frame.depths[matched.ids[m].first];
  return refinePoseHuber(matched.points_world, matched.pixels, static_inliers, camera_, pose_wc, options_.pnp.huber_px,
                         options_.pnp.refine_max_iterations, DepthMeasurements{match_depths, options_.depth_noise});
}

void Frontend::rememberMetricMotion(const Frame& frame, const Eigen::Isometry3d& pose_wc) {
  // A velocity is measured only between consecutive frames posed with depth. From a 2D-2D pose (its translation's
  // length a guess) the difference is mostly that pose's error: repeated as a velocity, a correction of 26 cm ran
  // away frame after frame (docs/frontend_generalisation.md, 2026-11-27).
  if (last_metric_frame_id_ + 1 == frame.id) {
    metric_velocity_ = last_pose_wc_->inverse() * pose_wc;  // the previous frame's pose is that metric one
    metric_velocity_seconds_ = frame.timestamp - last_measured_timestamp_;
  } else if (last_measured_frame_id_ + 1 == frame.id && metric_velocity_) {
    // The previous frame was posed 2D-2D: the motion model goes on from the last velocity measured with depth.
    // After coasted or skipped frames (predictions, not poses) it keeps its motion from the prediction: restarting
    // it there too was worse (fr3 made dark, ten draws: 4.47 cm mean against 4.21).
    motion_.reset();
    motion_.update(pose_wc * metric_velocity_->inverse(), frame.timestamp - metric_velocity_seconds_);
  }
  last_metric_frame_id_ = frame.id;
}

int Frontend::periodsBetween(double t0, double t1, std::size_t frames) const {
  // Without timestamps (no period learnt), a frame is a period.
  if (options_.motion_per_period && clock_.period()) return clock_.periodsBetween(t0, t1);
  return static_cast<int>(frames);
}

void Frontend::acceptPose(Frame& frame, TrackingResult& result, TrackingStatus status,
                          const Eigen::Isometry3d& pose_wc) {
  frame.pose_wc = pose_wc;
  result.status = status;
  setPose(result, frame.pose_wc);
  motion_.update(frame.pose_wc, frame.timestamp);
  last_pose_wc_ = frame.pose_wc;
  last_measured_frame_id_ = frame.id;
  last_measured_timestamp_ = frame.timestamp;
  if (dense_) dense_->acceptCurrent();
}

void Frontend::insertKeyframeIfNeeded(const Frame& frame, TrackingResult& result, const LocalMatches& matched,
                                      const std::vector<int>& static_inliers,
                                      const std::vector<Eigen::Vector2d>& dynamic_pixels) {
  const auto trackedPoints = [&] {
    std::vector<std::pair<std::size_t, MapPointId>> tracked;
    for (const int m : static_inliers) tracked.push_back(matched.ids[m]);
    return tracked;
  };
  // The gate is asked last: it costs ~25 ms and only keyframe candidates need it.
  if (!needsKeyframe(frame.pose_wc, static_inliers.size())) {
    if (options_.keyframe_before_loss) last_unkeyed_ = UnkeyedFrame{frame, trackedPoints(), dynamic_pixels};
    return;
  }
  // A candidate that barely tracks is never refused: its points may be what the next frame needs.
  if (refusedByQualityGate(result, static_inliers.size() < options_.quality.min_tracked_to_refuse)) return;
  insertKeyframe(frame, trackedPoints(), dynamic_pixels);
  setPose(result, frame.pose_wc);  // now relative to itself
  result.keyframe = true;
}

TrackingResult Frontend::initialize(Frame& frame, TrackingResult result) {
  const std::size_t with_depth = frame.withDepth();
  if (with_depth < options_.min_initial_points) {
    result.status = TrackingStatus::Lost;
    result.reason = "only " + std::to_string(with_depth) + " features with depth to start a map";
    return result;
  }
  // A new segment continues from the last known pose: mini-maps stay in one frame.
  frame.pose_wc = last_pose_wc_.value_or(Eigen::Isometry3d::Identity());
  transitionTo(FrontendState::Tracking);
  motion_.update(frame.pose_wc, frame.timestamp);
  last_pose_wc_ = frame.pose_wc;
  last_measured_frame_id_ = frame.id;
  last_measured_timestamp_ = frame.timestamp;
  last_tracked_frame_id_ = frame.id;
  last_metric_frame_id_ = frame.id;
  if (dense_) dense_->acceptCurrent();
  insertKeyframe(frame, {}, {});
  result.status = TrackingStatus::Initialized;
  setPose(result, frame.pose_wc);
  result.keyframe = true;
  result.inliers = tracked_at_last_keyframe_;
  return result;
}

std::optional<Eigen::Isometry3d> Frontend::predictPose() {
  const DenseOdometryUse use = options_.dense_odometry.use;
  if (dense_ && (use == DenseOdometryUse::Prior || use == DenseOdometryUse::PriorAndFallback))
    if (const auto motion = dense_->motionFromReference()) return *last_pose_wc_ * *motion;
  return options_.motion_per_period ? motion_.predict(current_timestamp_, clock_) : motion_.predict();
}

TrackingResult Frontend::trackWithoutFeatures(Frame& frame, TrackingResult result, const std::string& why_not_3d) {
  // An image the gate judges degraded (blur, noise) keeps the motion model's prediction: a 2D-2D or dense pose
  // from it is worse (fr3 with bursts of blurred, noisy frames: a 2D-2D pose 4 cm off, then one 8 cm off). The
  // fallbacks are for good images without depth.
  if (refusedByQualityGate(result)) return skipLowQuality(result, why_not_3d);
  std::string why = why_not_3d;
  const DenseOdometryUse use = options_.dense_odometry.use;
  if (dense_ && (use == DenseOdometryUse::Fallback || use == DenseOdometryUse::PriorAndFallback)) {
    if (const auto motion = dense_->motionFromReference()) {
      // Measured with depth, so it may scale a later 2D-2D estimate.
      const Eigen::Isometry3d pose_wc = *last_pose_wc_ * *motion;
      rememberMetricMotion(frame, pose_wc);
      acceptPose(frame, result, TrackingStatus::TrackedDense, pose_wc);
      result.reason = why_not_3d;
      insertDenseKeyframe(frame, result);
      return result;
    }
    why += "; dense odometry failed";
  }
  // A frame with depth lost its matches, not its depth: on real frames (fr3 Kinect-like, dim or blurred) a 2D-2D
  // pose there was a median 5 cm off where the prediction was 2 cm (docs/frontend_generalisation.md).
  if (canCoast(frame)) {
    predictPoseOf(result);
    if (result.pose_predicted) {
      result.status = TrackingStatus::Coasted;
      result.reason = why + "; kept the prediction";
      return result;
    }
  }
  return trackRelative(frame, result, why);
}

void Frontend::insertDenseKeyframe(const Frame& frame, TrackingResult& result) {
  // 3D-2D failed because the map has too few points this frame can match: without new ones it fails again, and
  // dense poses chained frame to frame drifted (fr3 made dark, draw 8: 89 dense frames in a row, 18 cm ATE). The
  // frame's own points, at the dense pose, give the next frame a map to track against (that draw: 2.0 cm).
  if (frame.withDepth() < options_.min_initial_points) return;
  insertKeyframe(frame, {}, {});
  setPose(result, frame.pose_wc);  // now relative to itself
  result.keyframe = true;
}

bool Frontend::canCoast(const Frame& frame) const {
  if (state_ != FrontendState::Tracking || !last_pose_wc_ || last_tracked_frame_id_ + 1 != frame.id) return false;
  return frame.withDepth() >= options_.min_initial_points;
}

TrackingResult Frontend::trackRelative(Frame& frame, TrackingResult result, const std::string& why_not_3d) {
  if (!metric_velocity_) return lose(result, why_not_3d + ", and no metric motion yet to scale a 2D-2D estimate");
  // The last motion measured with depth, not the motion model's (which 2D-2D
  // frames feed): a scale error would otherwise compound frame after frame. Once per frame (or frame period) since
  // the last measured frame, per one it spanned: frames skipped or coasted in between moved too.
  const std::size_t frames = frame.id - last_measured_frame_id_;
  const int periods = periodsBetween(last_measured_timestamp_, frame.timestamp, frames);
  Eigen::Isometry3d predicted_wc = *last_pose_wc_;
  const int spanned = periodsBetween(0.0, metric_velocity_seconds_, 1);  // the periods the velocity was measured over
  if (periods == static_cast<int>(frames) && spanned == 1)
    for (std::size_t k = 0; k < frames; ++k) predicted_wc = predicted_wc * *metric_velocity_;  // per frame, as ever
  else
    predicted_wc = predicted_wc * scaledMotion(*metric_velocity_, static_cast<double>(periods) / spanned);
  const Eigen::Isometry3d predicted_in_keyframe = last_keyframe_.pose_wc.inverse() * predicted_wc;
  std::vector<Eigen::Vector2d> keyframe_pixels, frame_pixels;
  matchLastKeyframe(frame, keyframe_pixels, frame_pixels);
  RelativeMotion relative = estimateRelativeMotion2d2d(keyframe_pixels, frame_pixels, camera_);
  if (!relative.ok) return lose(result, why_not_3d + "; 2D-2D: " + relative.failure);

  // The essential matrix gives the direction of travel; its length comes
  // from the constant-velocity prediction.
  const auto scaled = [&predicted_in_keyframe](Eigen::Isometry3d motion) {
    motion.translation() *= predicted_in_keyframe.translation().norm();
    return motion;
  };
  // Moving points by their epipolar distance under that motion; if any, the
  // motion is estimated again without them.
  const std::vector<bool> moving = flagDynamicByEpipolarDistance(
      keyframe_pixels, frame_pixels, scaled(relative.pose_2_in_1), camera_, options_.dynamic_filter);
  result.dynamic = static_cast<std::size_t>(std::count(moving.begin(), moving.end(), true));
  if (result.dynamic > 0) {
    std::vector<Eigen::Vector2d> static_keyframe, static_frame;
    for (std::size_t m = 0; m < moving.size(); ++m)
      if (!moving[m]) {
        static_keyframe.push_back(keyframe_pixels[m]);
        static_frame.push_back(frame_pixels[m]);
      }
    relative = estimateRelativeMotion2d2d(static_keyframe, static_frame, camera_);
    if (!relative.ok) return lose(result, why_not_3d + "; 2D-2D without moving points: " + relative.failure);
  }
  Eigen::Isometry3d motion = scaled(relative.pose_2_in_1);
  // Below about a degree of parallax the direction of travel is noise: keep
  // the measured rotation and the predicted translation.
  if (relative.median_parallax_deg < options_.min_parallax_deg)
    motion.translation() = predicted_in_keyframe.translation();
  acceptPose(frame, result, TrackingStatus::TrackedRelative, last_keyframe_.pose_wc * motion);
  result.reason = why_not_3d;
  result.matches = keyframe_pixels.size();
  result.inliers = relative.inliers.size();
  return result;
}

void Frontend::matchLastKeyframe(const Frame& frame, std::vector<Eigen::Vector2d>& keyframe_pixels,
                                 std::vector<Eigen::Vector2d>& frame_pixels) const {
  DescriptorMatcher keyframe_matcher(options_.matcher);
  keyframe_matcher.setReference(last_keyframe_.descriptors);
  for (const cv::DMatch& match : keyframe_matcher.match(frame.descriptors)) {
    keyframe_pixels.push_back(last_keyframe_.pixels[match.trainIdx]);
    frame_pixels.push_back(frame.pixels[match.queryIdx]);
  }
}

TrackingResult Frontend::lose(TrackingResult result, const std::string& reason) {
  if (refusedByQualityGate(result)) return skipLowQuality(result, reason);
  predictPoseOf(result);
  // A new segment starts at the next frame that can: from depth, it tracks the scene again at once, where
  // coasting on the prediction for a few frames kept the 2D-2D fallback going and drifted (fr3 blur: 3.7 -> 36 cm).
  keyLastTrackedFrame();
  transitionTo(FrontendState::Lost);
  result.status = TrackingStatus::Lost;
  result.reason = reason;
  return result;
}

void Frontend::keyLastTrackedFrame() {
  if (state_ != FrontendState::Tracking || !last_unkeyed_) return;
  // On fr3 with ten frames blacked out, the last keyframe before the loss was often ~10 frames before it, and the
  // new segment's first keyframes found too few PnP inliers against its view to be bridged.
  const UnkeyedFrame unkeyed = std::move(*last_unkeyed_);  // insertKeyframe clears last_unkeyed_
  insertKeyframe(unkeyed.frame, unkeyed.tracked, unkeyed.dynamic_pixels);
}

void Frontend::predictPoseOf(TrackingResult& result) {
  // The last measured pose (the 2D-2D scale, the dense odometry's reference) stays as it was.
  if (state_ != FrontendState::Tracking) return;
  const std::optional<Eigen::Isometry3d> predicted = predictPose();
  if (!predicted) return;
  result.pose_predicted = true;
  setPose(result, *predicted);
  motion_.update(*predicted, current_timestamp_);
}

void Frontend::setPose(TrackingResult& result, const Eigen::Isometry3d& pose_wc) const {
  result.pose_wc = pose_wc;
  result.reference_keyframe = last_keyframe_id_;
  // Relative to the keyframe as the backend has it now, which is what the
  // map points this pose was tracked against are expressed with.
  const Eigen::Isometry3d reference = map_.keyframePose(last_keyframe_id_).value_or(last_keyframe_.pose_wc);
  result.pose_in_reference = reference.inverse() * pose_wc;
}

bool Frontend::needsKeyframe(const Eigen::Isometry3d& pose_wc, std::size_t tracked) const {
  const Eigen::Isometry3d since_keyframe = last_keyframe_.pose_wc.inverse() * pose_wc;
  return since_keyframe.translation().norm() > options_.keyframe_translation_m ||
         rotationAngleDeg(since_keyframe) > options_.keyframe_rotation_deg ||
         static_cast<double>(tracked) < options_.keyframe_min_tracked_ratio * tracked_at_last_keyframe_;
}

void Frontend::insertKeyframe(const Frame& frame, const std::vector<std::pair<std::size_t, MapPointId>>& tracked,
                              const std::vector<Eigen::Vector2d>& dynamic_pixels) {
  Keyframe keyframe;
  keyframe.frame_id = frame.id;
  keyframe.timestamp = frame.timestamp;
  keyframe.pose_wc = frame.pose_wc;
  keyframe.segment = segment_;
  keyframe.keypoints = frame.keypoints;
  keyframe.descriptors = frame.descriptors.clone();  // the keyframe outlives the frame's buffers
  keyframe.pixels = frame.pixels;
  keyframe.depths = frame.depths;
  const KeyframeId keyframe_id = map_.addKeyframe(keyframe);
  last_keyframe_id_ = keyframe_id;
  last_unkeyed_.reset();  // a frame older than a keyframe adds nothing
  recordKeyframePlanes(frame);
  const std::vector<bool> used = observeTrackedPoints(keyframe_id, frame, tracked);
  createMapPoints(keyframe_id, frame, used, dynamic_pixels);
  last_keyframe_ = frame;
  tracked_at_last_keyframe_ = tracked.size();  // 0 at a segment's first keyframe: motion decides the next
  backend_.keyframeInserted();
}

std::vector<bool> Frontend::observeTrackedPoints(KeyframeId keyframe, const Frame& frame,
                                                 const std::vector<std::pair<std::size_t, MapPointId>>& tracked) {
  std::vector<bool> used(frame.size(), false);
  for (const auto& [feature, point_id] : tracked) {
    used[feature] = true;
    recordKeyframePixel(point_id, frame, feature);
    const auto point = map_.mapPoint(point_id);
    if (!point) continue;  // removed by the backend meanwhile
    const MapPointObservation observation{keyframe, frame.pixels[feature], frame.depths[feature]};
    FusedPoint fused{point->position, point->covariance};
    if (frame.hasDepth(feature)) {
      const FusedPoint measured =
          measuredPoint(camera_, options_.depth_noise, frame.pose_wc, frame.pixels[feature], frame.depths[feature]);
      fused = fusePointEstimates({point->position, measured.position}, {point->covariance, measured.covariance});
    }
    map_.addObservation(point_id, observation, fused.position, fused.covariance,
                        frame.descriptors.row(feature).clone());
  }
  return used;
}

void Frontend::createMapPoints(KeyframeId keyframe, const Frame& frame, const std::vector<bool>& used,
                               const std::vector<Eigen::Vector2d>& dynamic_pixels) {
  const double mask_sq = options_.dynamic_mask_radius_px * options_.dynamic_mask_radius_px;
  for (std::size_t i = 0; i < frame.size(); ++i) {
    if (used[i] || !frame.hasDepth(i)) continue;
    const bool near_moving = std::any_of(dynamic_pixels.begin(), dynamic_pixels.end(), [&](const Eigen::Vector2d& p) {
      return (p - frame.pixels[i]).squaredNorm() < mask_sq;
    });
    if (!near_moving) createMapPoint(keyframe, frame, i);
  }
}

void Frontend::createMapPoint(KeyframeId keyframe, const Frame& frame, std::size_t feature) {
  const FusedPoint measured =
      measuredPoint(camera_, options_.depth_noise, frame.pose_wc, frame.pixels[feature], frame.depths[feature]);
  MapPoint point;
  point.position = measured.position;
  point.covariance = measured.covariance;
  point.descriptor = frame.descriptors.row(feature).clone();
  point.observations.push_back({keyframe, frame.pixels[feature], frame.depths[feature]});
  recordKeyframePixel(map_.addMapPoint(std::move(point)), frame, feature);
}

}  // namespace weighted_icp::frontend
