#include "weighted_icp/frontend/geometry/pose_estimation.h"

#include <cmath>
#include <stdexcept>
#include <utility>

#include <ceres/loss_function.h>
#include <ceres/problem.h>
#include <ceres/solver.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>  // after Eigen (via pose_estimation.h), which it needs

#include "input_checks.h"
#include "solver_options.h"
#include "weighted_icp/frontend/geometry/reprojection_residual.h"

namespace weighted_icp::frontend {

namespace {

constexpr int kMinPnpMatches = 4;  // AP3P's minimal set

std::optional<std::string> pnpOptionsProblem(const PnpOptions& options) {
  if (options.ransac_iterations < 1) return "ransac_iterations must be at least 1";
  if (!(options.ransac_reprojection_px > 0 && std::isfinite(options.ransac_reprojection_px)))
    return "ransac_reprojection_px must be positive";
  if (!(options.confidence > 0 && options.confidence < 1)) return "confidence must be in (0, 1)";
  if (options.min_inliers < kMinPnpMatches) return "min_inliers must be at least 4";
  if (!(options.huber_px > 0)) return "huber_px must be positive";
  if (options.refine_max_iterations < 0) return "refine_max_iterations must not be negative";
  return std::nullopt;
}

/// The candidates in front of the camera whose reprojection error is at most `threshold_px`.
std::vector<int> selectInliers(const std::vector<Eigen::Vector3d>& points_world,
                               const std::vector<Eigen::Vector2d>& pixels, const std::vector<int>& candidates,
                               const PinholeCamera& camera, const Eigen::Isometry3d& pose_wc, double threshold_px) {
  const Eigen::Isometry3d pose_cw = pose_wc.inverse();
  std::vector<int> inliers;
  for (const int i : candidates) {
    const Eigen::Vector3d p = pose_cw * points_world[i];
    if (p.z() < kMinPointDepth) continue;
    if ((camera.project(p) - pixels[i]).norm() <= threshold_px) inliers.push_back(i);
  }
  return inliers;
}

double rmsReprojection(const std::vector<Eigen::Vector3d>& points_world, const std::vector<Eigen::Vector2d>& pixels,
                       const std::vector<int>& use, const PinholeCamera& camera, const Eigen::Isometry3d& pose_wc) {
  if (use.empty()) return 0.0;
  const Eigen::Isometry3d pose_cw = pose_wc.inverse();
  double sum = 0.0;
  for (const int i : use) sum += (camera.project(pose_cw * points_world[i]) - pixels[i]).squaredNorm();
  return std::sqrt(sum / static_cast<double>(use.size()));
}

/// RANSAC PnP over `valid` matches; returns the pose and its inliers (input
/// indices), or no inliers when RANSAC finds no model.
std::pair<Eigen::Isometry3d, std::vector<int>> ransacPnp(const std::vector<Eigen::Vector3d>& points_world,
                                                         const std::vector<Eigen::Vector2d>& pixels,
                                                         const std::vector<int>& valid, const PinholeCamera& camera,
                                                         const PnpOptions& options) {
  std::vector<cv::Point3d> object_points;
  std::vector<cv::Point2d> image_points;
  object_points.reserve(valid.size());
  image_points.reserve(valid.size());
  for (const int i : valid) {
    object_points.emplace_back(points_world[i].x(), points_world[i].y(), points_world[i].z());
    image_points.emplace_back(pixels[i].x(), pixels[i].y());
  }
  cv::Mat rvec, tvec;
  std::vector<int> consensus;
  bool found = false;
  try {
    // AP3P: 4-point minimal sets (fewer draws than EPnP's 5 at a given outlier
    // rate); OpenCV then fits EPnP to the consensus.
    found = cv::solvePnPRansac(object_points, image_points, cv::Mat(camera.cameraMatrix()), cv::noArray(), rvec, tvec,
                               false, options.ransac_iterations, static_cast<float>(options.ransac_reprojection_px),
                               options.confidence, consensus,
                               options.method == PnpMethod::Iterative ? cv::SOLVEPNP_ITERATIVE : cv::SOLVEPNP_AP3P);
  } catch (const cv::Exception&) {
    found = false;  // degenerate samples (e.g. all points collinear) raise in the minimal solvers
  }
  if (!found || rvec.empty() || tvec.empty()) return {Eigen::Isometry3d::Identity(), {}};

  cv::Matx33d rotation_cv;
  cv::Rodrigues(rvec, rotation_cv);
  Eigen::Matrix3d rotation;
  cv::cv2eigen(rotation_cv, rotation);
  Eigen::Vector3d translation;
  cv::cv2eigen(tvec, translation);
  Eigen::Isometry3d pose_cw = Eigen::Isometry3d::Identity();
  pose_cw.linear() = rotation;
  pose_cw.translation() = translation;
  if (!detail::isRigid(pose_cw)) return {Eigen::Isometry3d::Identity(), {}};

  std::vector<int> inliers;
  inliers.reserve(consensus.size());
  for (const int k : consensus) inliers.push_back(valid[k]);
  return {pose_cw.inverse(), inliers};
}

Eigen::Isometry3d refinePose(const std::vector<Eigen::Vector3d>& points_world,
                             const std::vector<Eigen::Vector2d>& pixels, const std::vector<int>& use,
                             const PinholeCamera& camera, const Eigen::Isometry3d& initial_wc, double huber_px,
                             int max_iterations, const DepthMeasurements* depth) {
  if (points_world.size() != pixels.size())
    throw std::invalid_argument("refinePoseHuber: " + std::to_string(points_world.size()) + " points but " +
                                std::to_string(pixels.size()) + " pixels");
  if (const auto problem = detail::cameraProblem(camera)) throw std::invalid_argument("refinePoseHuber: " + *problem);
  if (!(huber_px > 0)) throw std::invalid_argument("refinePoseHuber: huber_px must be positive");
  if (max_iterations < 0) throw std::invalid_argument("refinePoseHuber: max_iterations must not be negative");
  if (!detail::isRigid(initial_wc)) throw std::invalid_argument("refinePoseHuber: initial pose is not rigid");
  for (const int i : use) {
    if (i < 0 || i >= static_cast<int>(points_world.size()))
      throw std::invalid_argument("refinePoseHuber: index " + std::to_string(i) + " out of range");
    if (!points_world[i].allFinite() || !pixels[i].allFinite())
      throw std::invalid_argument("refinePoseHuber: match " + std::to_string(i) + " is not finite");
  }

  PoseParameters pose = PoseParameters::fromPoseWc(initial_wc);
  std::vector<int> in_front;
  for (const int i : use)
    if (pose.toCamera(points_world[i]).z() >= kMinPointDepth) in_front.push_back(i);
  if (in_front.size() < 3 || max_iterations == 0) return initial_wc;

  ceres::Problem problem;
  // Infinity means plain least squares (no loss function).
  ceres::LossFunction* loss = std::isfinite(huber_px) ? new ceres::HuberLoss(huber_px) : nullptr;
  problem.AddParameterBlock(pose.data(), 7, new PoseManifold);
  // Points held constant: copies, since Ceres takes mutable parameter blocks.
  std::vector<Eigen::Vector3d> points(points_world);
  for (const int i : in_front) {
    const double z = depth ? depth->depths[i] : 0.0;
    if (z > 0.0) {
      problem.AddResidualBlock(new RgbdResidual(camera, pixels[i], 1.0, z, depth->noise.sigmaDepth(z)), loss,
                               pose.data(), points[i].data());
      problem.SetParameterBlockConstant(points[i].data());
    } else {
      problem.AddResidualBlock(new PoseOnlyReprojectionResidual(camera, points_world[i], pixels[i], 1.0), loss,
                               pose.data());
    }
  }

  ceres::Solver::Summary summary;
  ceres::Solve(detail::levenbergMarquardt(max_iterations), &problem, &summary);
  if (!summary.IsSolutionUsable()) return initial_wc;
  return pose.poseWc();
}

/// What makes estimatePosePnp's input unusable (mismatched sizes, a bad camera, bad options, a guess that is not
/// rigid), as its failure message; nothing when it can run.
std::optional<std::string> pnpInputProblem(const std::vector<Eigen::Vector3d>& points_world,
                                           const std::vector<Eigen::Vector2d>& pixels, const PinholeCamera& camera,
                                           const std::optional<Eigen::Isometry3d>& guess_wc,
                                           const PnpOptions& options) {
  if (points_world.size() != pixels.size())
    return "mismatched sizes: " + std::to_string(points_world.size()) + " points, " + std::to_string(pixels.size()) +
           " pixels";
  if (auto problem = detail::cameraProblem(camera)) return problem;
  if (const auto problem = pnpOptionsProblem(options)) return "invalid options: " + *problem;
  if (guess_wc && !detail::isRigid(*guess_wc)) return std::string("the guess is not a rigid transform");
  return std::nullopt;
}

/// A pose, the matches within `ransac_reprojection_px` of it, and whether it came from the guess.
struct PoseCandidate {
  Eigen::Isometry3d pose_wc = Eigen::Isometry3d::Identity();
  std::vector<int> inliers;
  bool from_guess = false;
};

/// Where refinement starts: RANSAC's hypothesis and its consensus, or the guess and the matches it explains when
/// those are more.
PoseCandidate startingPose(const std::vector<Eigen::Vector3d>& points_world, const std::vector<Eigen::Vector2d>& pixels,
                           const std::vector<int>& valid, const PinholeCamera& camera,
                           const std::optional<Eigen::Isometry3d>& guess_wc, const PnpOptions& options) {
  auto [ransac_wc, ransac_inliers] = ransacPnp(points_world, pixels, valid, camera, options);
  if (guess_wc) {
    std::vector<int> guess_inliers =
        selectInliers(points_world, pixels, valid, camera, *guess_wc, options.ransac_reprojection_px);
    if (guess_inliers.size() > ransac_inliers.size()) return {*guess_wc, std::move(guess_inliers), true};
  }
  return {ransac_wc, std::move(ransac_inliers), false};
}

/// The Huber refinement from `start_wc` on `start_inliers`, and the matches within the RANSAC threshold after it.
PoseCandidate refineCandidate(const std::vector<Eigen::Vector3d>& points_world,
                              const std::vector<Eigen::Vector2d>& pixels, const std::vector<int>& valid,
                              const PinholeCamera& camera, const Eigen::Isometry3d& start_wc,
                              const std::vector<int>& start_inliers, const PnpOptions& options) {
  PoseCandidate candidate;
  candidate.pose_wc = refinePose(points_world, pixels, start_inliers, camera, start_wc, options.huber_px,
                                 options.refine_max_iterations, nullptr);
  candidate.inliers =
      selectInliers(points_world, pixels, valid, camera, candidate.pose_wc, options.ransac_reprojection_px);
  return candidate;
}

/// The guess refined on the matches it explains within twice the inlier radius, when there are enough of them. Twice:
/// a prediction off by a few pixels (half a degree at 525 px focal length, or a sideways step traded for a turn on far
/// landmarks) explains almost none of its matches within the inlier radius but most within twice it.
std::optional<PoseCandidate> guessCandidate(const std::vector<Eigen::Vector3d>& points_world,
                                            const std::vector<Eigen::Vector2d>& pixels, const std::vector<int>& valid,
                                            const PinholeCamera& camera, const Eigen::Isometry3d& guess_wc,
                                            const PnpOptions& options) {
  const std::vector<int> near =
      selectInliers(points_world, pixels, valid, camera, guess_wc, 2.0 * options.ransac_reprojection_px);
  if (static_cast<int>(near.size()) < options.min_inliers) return std::nullopt;
  PoseCandidate candidate = refineCandidate(points_world, pixels, valid, camera, guess_wc, near, options);
  candidate.from_guess = true;
  return candidate;
}

}  // namespace

Eigen::Isometry3d refinePoseHuber(const std::vector<Eigen::Vector3d>& points_world,
                                  const std::vector<Eigen::Vector2d>& pixels, const std::vector<int>& use,
                                  const PinholeCamera& camera, const Eigen::Isometry3d& initial_wc, double huber_px,
                                  int max_iterations) {
  return refinePose(points_world, pixels, use, camera, initial_wc, huber_px, max_iterations, nullptr);
}

Eigen::Isometry3d refinePoseHuber(const std::vector<Eigen::Vector3d>& points_world,
                                  const std::vector<Eigen::Vector2d>& pixels, const std::vector<int>& use,
                                  const PinholeCamera& camera, const Eigen::Isometry3d& initial_wc, double huber_px,
                                  int max_iterations, const DepthMeasurements& depth) {
  if (depth.depths.size() != points_world.size())
    throw std::invalid_argument("refinePoseHuber: " + std::to_string(depth.depths.size()) + " depths for " +
                                std::to_string(points_world.size()) + " points");
  return refinePose(points_world, pixels, use, camera, initial_wc, huber_px, max_iterations, &depth);
}

PoseEstimate estimatePosePnp(const std::vector<Eigen::Vector3d>& points_world,
                             const std::vector<Eigen::Vector2d>& pixels, const PinholeCamera& camera,
                             const std::optional<Eigen::Isometry3d>& guess_wc, const PnpOptions& options) {
  PoseEstimate estimate;
  if (auto problem = pnpInputProblem(points_world, pixels, camera, guess_wc, options)) {
    estimate.failure = std::move(*problem);
    return estimate;
  }
  std::vector<int> valid;
  valid.reserve(points_world.size());
  for (std::size_t i = 0; i < points_world.size(); ++i)
    if (points_world[i].allFinite() && pixels[i].allFinite()) valid.push_back(static_cast<int>(i));
  if (static_cast<int>(valid.size()) < options.min_inliers) {
    estimate.failure = "too few matches: " + std::to_string(valid.size()) + " finite, " +
                       std::to_string(options.min_inliers) + " needed";
    return estimate;
  }

  const PoseCandidate start = startingPose(points_world, pixels, valid, camera, guess_wc, options);
  estimate.initial_from_guess = start.from_guess;
  const bool enough_to_start = static_cast<int>(start.inliers.size()) >= options.min_inliers;
  PoseCandidate best;
  if (enough_to_start) {
    estimate.initial_pose_wc = start.pose_wc;
    best = refineCandidate(points_world, pixels, valid, camera, start.pose_wc, start.inliers, options);
  }
  // Refining the guess on its wider neighbourhood is a second candidate unless refinement already starts there.
  if (guess_wc && options.refine_guess && !(estimate.initial_from_guess && enough_to_start)) {
    if (auto from_guess = guessCandidate(points_world, pixels, valid, camera, *guess_wc, options);
        from_guess && from_guess->inliers.size() > best.inliers.size()) {
      best = std::move(*from_guess);
      estimate.initial_pose_wc = *guess_wc;
      estimate.refined_from_guess = true;
    }
  }
  if (!enough_to_start && !estimate.refined_from_guess) {
    estimate.failure = "RANSAC found " + std::to_string(start.inliers.size()) + " inliers, " +
                       std::to_string(options.min_inliers) + " needed";
    return estimate;
  }
  const Eigen::Isometry3d refined_wc = best.pose_wc;
  std::vector<int> inliers = std::move(best.inliers);
  if (static_cast<int>(inliers.size()) < options.min_inliers) {
    estimate.failure = "refined pose keeps " + std::to_string(inliers.size()) + " inliers, " +
                       std::to_string(options.min_inliers) + " needed";
    return estimate;
  }
  estimate.ok = true;
  estimate.pose_wc = refined_wc;
  estimate.rms_reprojection_px = rmsReprojection(points_world, pixels, inliers, camera, refined_wc);
  estimate.inliers = std::move(inliers);
  return estimate;
}

}  // namespace weighted_icp::frontend
