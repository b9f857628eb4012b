// The 2D-2D fallback of pose_estimation.h: essential matrix or homography.

#include <algorithm>
#include <cmath>
#include <optional>

#include <ceres/autodiff_cost_function.h>
#include <ceres/loss_function.h>
#include <ceres/manifold.h>
#include <ceres/problem.h>
#include <ceres/solver.h>
#include <ceres/sphere_manifold.h>
#include <Eigen/Geometry>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>  // after Eigen, which it needs

#include "input_checks.h"
#include "solver_options.h"
#include "weighted_icp/core/statistics.h"
#include "weighted_icp/frontend/geometry/pose_estimation.h"

namespace weighted_icp::frontend {

namespace {

constexpr int kMinMatches = 8;
constexpr double kRansacConfidence = 0.999;
constexpr int kRansacMaxIterations = 200;  // as ORB-SLAM; a homography of a general scene would use them all
constexpr double kChi2OneDof = 3.841;      // 95 % quantiles
constexpr double kChi2TwoDof = 5.991;
constexpr double kHomographyScoreRatio = 0.45;
constexpr int kRefineMaxIterations = 100;
// RANSAC's inliers are those of a noisy minimal-sample model: refining, then
// re-selecting the inliers under the refined model and refining again recovers
// the matches it wrongly rejected (the translation direction error halves).
constexpr int kRefineRounds = 3;

/// Inlier bounds and score scale for matches with noise sigma per coordinate in both images.
struct NoiseBounds {
  double essential_px;    // Sampson distance: 1 dof, sigma
  double homography_px;   // transfer error: 2 dof, sqrt(2) sigma (both pixels)
  double match_variance;  // of a transfer error or a distance to an epipolar line: 2 sigma^2

  explicit NoiseBounds(double sigma)
      : essential_px(std::sqrt(kChi2OneDof) * sigma),
        homography_px(std::sqrt(2.0 * kChi2TwoDof) * sigma),
        match_variance(2.0 * sigma * sigma) {}
};

cv::Vec3d homogeneous(const cv::Point2d& p) { return {p.x, p.y, 1.0}; }

// ORB-SLAM's model scores: each passing side adds (5.991 - chi2), for both
// models, so neither is favoured for its dof.
double transferScore(const cv::Matx33d& homography, const cv::Point2d& from, const cv::Point2d& to, double variance) {
  const cv::Vec3d mapped = homography * homogeneous(from);
  if (std::abs(mapped[2]) < 1e-12) return 0.0;
  const double dx = mapped[0] / mapped[2] - to.x, dy = mapped[1] / mapped[2] - to.y;
  const double chi2 = (dx * dx + dy * dy) / variance;
  return chi2 < kChi2TwoDof ? kChi2TwoDof - chi2 : 0.0;
}

double homographyScore(const cv::Matx33d& h21, const std::vector<cv::Point2d>& p1, const std::vector<cv::Point2d>& p2,
                       double variance) {
  const cv::Matx33d h12 = h21.inv();
  double score = 0.0;
  for (std::size_t i = 0; i < p1.size(); ++i)
    score += transferScore(h21, p1[i], p2[i], variance) + transferScore(h12, p2[i], p1[i], variance);
  return score;
}

double epipolarScore(const cv::Vec3d& line, const cv::Point2d& point, double variance) {
  const double norm2 = line[0] * line[0] + line[1] * line[1];
  if (norm2 < 1e-24) return 0.0;
  const double distance = line.dot(homogeneous(point));
  const double chi2 = distance * distance / norm2 / variance;
  return chi2 < kChi2OneDof ? kChi2TwoDof - chi2 : 0.0;
}

double fundamentalScore(const cv::Matx33d& f21, const std::vector<cv::Point2d>& p1, const std::vector<cv::Point2d>& p2,
                        double variance) {
  double score = 0.0;
  for (std::size_t i = 0; i < p1.size(); ++i)
    score += epipolarScore(f21 * homogeneous(p1[i]), p2[i], variance) +
             epipolarScore(f21.t() * homogeneous(p2[i]), p1[i], variance);
  return score;
}

/// The `candidates` (indices into p1/p2) that triangulate in front of both
/// cameras for x2 = R x1 + t, and the angles between their viewing rays.
struct Triangulation {
  std::vector<int> in_front;
  std::vector<double> parallax_deg;
};

Triangulation triangulateInFront(const cv::Matx33d& camera_matrix, const cv::Matx33d& rotation,
                                 const cv::Vec3d& translation, const std::vector<cv::Point2d>& p1,
                                 const std::vector<cv::Point2d>& p2, const std::vector<int>& candidates) {
  if (candidates.empty()) return {};
  cv::Matx34d projection1 = cv::Matx34d::eye(), projection2;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) projection2(r, c) = rotation(r, c);
    projection2(r, 3) = translation[r];
  }
  projection1 = camera_matrix * projection1;
  projection2 = camera_matrix * projection2;
  cv::Mat pixels1(2, static_cast<int>(candidates.size()), CV_64F), pixels2(pixels1.size(), CV_64F);
  for (std::size_t k = 0; k < candidates.size(); ++k) {
    pixels1.at<double>(0, static_cast<int>(k)) = p1[candidates[k]].x;
    pixels1.at<double>(1, static_cast<int>(k)) = p1[candidates[k]].y;
    pixels2.at<double>(0, static_cast<int>(k)) = p2[candidates[k]].x;
    pixels2.at<double>(1, static_cast<int>(k)) = p2[candidates[k]].y;
  }
  cv::Mat points4;
  cv::triangulatePoints(projection1, projection2, pixels1, pixels2, points4);
  const cv::Vec3d center2 = -(rotation.t() * translation);  // in camera 1's frame
  Triangulation triangulation;
  for (std::size_t k = 0; k < candidates.size(); ++k) {
    const int col = static_cast<int>(k);
    const double w = points4.at<double>(3, col);
    if (std::abs(w) < 1e-12) continue;  // at infinity: no depth to check
    const cv::Vec3d x1(points4.at<double>(0, col) / w, points4.at<double>(1, col) / w, points4.at<double>(2, col) / w);
    const cv::Vec3d x2 = rotation * x1 + translation;
    if (!(x1[2] > 0 && x2[2] > 0 && std::isfinite(x1[2]) && std::isfinite(x2[2]))) continue;
    triangulation.in_front.push_back(candidates[k]);
    const cv::Vec3d ray2 = x1 - center2;
    triangulation.parallax_deg.push_back(
        std::acos(std::clamp(x1.dot(ray2) / (cv::norm(x1) * cv::norm(ray2)), -1.0, 1.0)) * 180.0 / CV_PI);
  }
  return triangulation;
}

std::vector<int> maskIndices(const cv::Mat& mask) {
  std::vector<int> indices;
  for (int i = 0; i < static_cast<int>(mask.total()); ++i)
    if (mask.ptr<uchar>()[i]) indices.push_back(i);
  return indices;
}

/// Sampson distance, in pixels, of a match to the epipolar geometry of
/// x2 = R(q) x1 + t; the pixels are given normalised (K^-1 x).
struct SampsonDistance {
  Eigen::Vector3d normalized1, normalized2;
  double inverse_fx2, inverse_fy2;  // 1 / fx^2, 1 / fy^2: F x1 = K^-T E K^-1 x1 in pixels

  template <typename T>
  bool operator()(const T* q_21, const T* t_21, T* residual) const {
    const Eigen::Map<const Eigen::Quaternion<T>> rotation(q_21);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t(t_21);
    Eigen::Matrix<T, 3, 3> t_cross;
    t_cross << T(0), -t.z(), t.y(), t.z(), T(0), -t.x(), -t.y(), t.x(), T(0);
    const Eigen::Matrix<T, 3, 3> essential = t_cross * rotation.toRotationMatrix();
    const Eigen::Matrix<T, 3, 1> line2 = essential * normalized1.cast<T>();
    const Eigen::Matrix<T, 3, 1> line1 = essential.transpose() * normalized2.cast<T>();
    const T gradient2 = (line2.x() * line2.x() + line1.x() * line1.x()) * inverse_fx2 +
                        (line2.y() * line2.y() + line1.y() * line1.y()) * inverse_fy2;
    if (!(gradient2 > T(1e-30))) return false;  // at an epipole: undefined
    residual[0] = normalized2.cast<T>().dot(line2) / sqrt(gradient2);
    return true;
  }
};

SampsonDistance sampsonDistance(const PinholeCamera& camera, const cv::Point2d& p1, const cv::Point2d& p2) {
  return {{(p1.x - camera.cx) / camera.fx, (p1.y - camera.cy) / camera.fy, 1.0},
          {(p2.x - camera.cx) / camera.fx, (p2.y - camera.cy) / camera.fy, 1.0},
          1.0 / (camera.fx * camera.fx),
          1.0 / (camera.fy * camera.fy)};
}

/// Levenberg-Marquardt on the Sampson distances of `use` (Huber): the
/// essential matrix from RANSAC comes from a minimal sample and is noisy.
/// Rotation on the quaternion manifold, translation on the unit sphere.
void refineEssentialMotion(const PinholeCamera& camera, const std::vector<cv::Point2d>& p1,
                           const std::vector<cv::Point2d>& p2, const std::vector<int>& use, double huber_px,
                           cv::Matx33d& rotation, cv::Vec3d& translation) {
  Eigen::Matrix3d r;
  cv::cv2eigen(rotation, r);
  Eigen::Quaterniond q(r);
  q.normalize();
  Eigen::Vector3d t;
  cv::cv2eigen(translation, t);
  t.normalize();

  ceres::Problem problem;
  problem.AddParameterBlock(q.coeffs().data(), 4, new ceres::EigenQuaternionManifold);
  problem.AddParameterBlock(t.data(), 3, new ceres::SphereManifold<3>);
  auto* loss = new ceres::HuberLoss(huber_px);
  for (const int i : use)
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<SampsonDistance, 1, 4, 3>(
                                 new SampsonDistance(sampsonDistance(camera, p1[i], p2[i]))),
                             loss, q.coeffs().data(), t.data());
  ceres::Solver::Summary summary;
  ceres::Solve(detail::levenbergMarquardt(kRefineMaxIterations), &problem, &summary);
  if (!summary.IsSolutionUsable() || !q.coeffs().allFinite() || !t.allFinite()) return;
  cv::eigen2cv(Eigen::Matrix3d(q.normalized().toRotationMatrix()), rotation);
  cv::eigen2cv(Eigen::Vector3d(t.normalized()), translation);
}

/// The matches within `threshold_px` (Sampson) of the epipolar geometry of x2 = R x1 + t.
std::vector<int> epipolarInliers(const PinholeCamera& camera, const std::vector<cv::Point2d>& p1,
                                 const std::vector<cv::Point2d>& p2, const cv::Matx33d& rotation,
                                 const cv::Vec3d& translation, double threshold_px) {
  Eigen::Matrix3d r;
  cv::cv2eigen(rotation, r);
  const Eigen::Quaterniond q(r);
  const Eigen::Vector3d t(translation[0], translation[1], translation[2]);
  std::vector<int> inliers;
  for (std::size_t i = 0; i < p1.size(); ++i) {
    double distance = 0.0;
    if (sampsonDistance(camera, p1[i], p2[i])(q.coeffs().data(), t.data(), &distance) &&
        std::abs(distance) <= threshold_px)
      inliers.push_back(static_cast<int>(i));
  }
  return inliers;
}

/// The motion x2 = R x1 + t as the pose of camera 2 in camera 1, with unit translation.
std::optional<Eigen::Isometry3d> poseOfSecondInFirst(const cv::Matx33d& rotation, const cv::Vec3d& translation) {
  Eigen::Matrix3d r;
  Eigen::Vector3d t;
  cv::cv2eigen(rotation, r);
  cv::cv2eigen(translation, t);
  Eigen::Isometry3d pose_21 = Eigen::Isometry3d::Identity();
  pose_21.linear() = r;
  pose_21.translation() = t;
  if (!detail::isRigid(pose_21) || t.norm() < 1e-12) return std::nullopt;
  Eigen::Isometry3d pose_12 = pose_21.inverse();
  pose_12.translation().normalize();
  return pose_12;
}

/// A motion recovered from one model: rotation, unit translation and the matches in front of both cameras.
struct TwoViewSolution {
  cv::Matx33d rotation;
  cv::Vec3d translation;
  Triangulation inliers;
};

/// Of the homography's decompositions, the one with most of its inlier matches in front of both cameras.
TwoViewSolution motionFromHomography(const cv::Mat& homography, const cv::Mat& homography_mask,
                                     const cv::Matx33d& camera_matrix, const std::vector<cv::Point2d>& p1,
                                     const std::vector<cv::Point2d>& p2) {
  TwoViewSolution solution;
  std::vector<cv::Mat> rotations, translations, normals;
  cv::decomposeHomographyMat(homography, camera_matrix, rotations, translations, normals);
  const std::vector<int> candidates = maskIndices(homography_mask);
  for (std::size_t s = 0; s < rotations.size(); ++s) {
    const cv::Matx33d r(rotations[s]);
    cv::Vec3d t(translations[s]);
    if (cv::norm(t) < 1e-12) continue;  // pure rotation: no depth to tell the solutions apart
    t /= cv::norm(t);
    Triangulation triangulation = triangulateInFront(camera_matrix, r, t, p1, p2, candidates);
    if (triangulation.in_front.size() > solution.inliers.in_front.size()) {
      solution.inliers = std::move(triangulation);
      solution.rotation = r;
      solution.translation = t;
    }
  }
  return solution;
}

/// The essential matrix's motion (recoverPose picks the decomposition with most points in front of both cameras),
/// refined on its epipolar inliers and the inliers chosen again until they settle.
TwoViewSolution motionFromEssential(const cv::Mat& essential, const cv::Mat& essential_mask,
                                    const PinholeCamera& camera, const std::vector<cv::Point2d>& p1,
                                    const std::vector<cv::Point2d>& p2, double essential_px) {
  const cv::Matx33d camera_matrix = camera.cameraMatrix();
  TwoViewSolution solution;
  cv::Mat r, t;
  cv::Mat mask = essential_mask.clone();
  cv::recoverPose(essential, p1, p2, camera_matrix, r, t, mask);
  solution.rotation = cv::Matx33d(r);
  solution.translation = cv::Vec3d(t);
  Triangulation& inliers = solution.inliers;
  inliers.in_front = maskIndices(mask);
  for (int round = 0; round < kRefineRounds && static_cast<int>(inliers.in_front.size()) >= kMinMatches; ++round) {
    refineEssentialMotion(camera, p1, p2, inliers.in_front, essential_px, solution.rotation, solution.translation);
    Triangulation reselected =
        triangulateInFront(camera_matrix, solution.rotation, solution.translation, p1, p2,
                           epipolarInliers(camera, p1, p2, solution.rotation, solution.translation, essential_px));
    const bool settled = reselected.in_front == inliers.in_front;
    inliers = std::move(reselected);
    if (settled) break;
  }
  return solution;
}

/// Fits both models to the finite matches p1/p2 and recovers the motion; the
/// inliers index p1/p2. OpenCV may throw on degenerate matches.
RelativeMotion fitTwoViewMotion(const std::vector<cv::Point2d>& p1, const std::vector<cv::Point2d>& p2,
                                const PinholeCamera& camera, const NoiseBounds& bounds) {
  RelativeMotion motion;
  const cv::Matx33d camera_matrix = camera.cameraMatrix();
  cv::Mat essential_mask, homography_mask;
  const cv::Mat essential = cv::findEssentialMat(p1, p2, camera_matrix, cv::RANSAC, kRansacConfidence,
                                                 bounds.essential_px, kRansacMaxIterations, essential_mask);
  const cv::Mat homography = cv::findHomography(p1, p2, cv::RANSAC, bounds.homography_px, homography_mask,
                                                kRansacMaxIterations, kRansacConfidence);
  const bool has_essential = essential.rows == 3 && essential.cols == 3;
  const bool has_homography = homography.rows == 3 && homography.cols == 3;
  if (!has_essential && !has_homography) {
    motion.failure = "RANSAC found neither an essential matrix nor a homography";
    return motion;
  }
  const cv::Matx33d camera_inverse = camera_matrix.inv();
  const double essential_score = has_essential
                                     ? fundamentalScore(camera_inverse.t() * cv::Matx33d(essential) * camera_inverse,
                                                        p1, p2, bounds.match_variance)
                                     : 0.0;
  const double homography_score =
      has_homography ? homographyScore(cv::Matx33d(homography), p1, p2, bounds.match_variance) : 0.0;
  if (essential_score + homography_score <= 0.0) {
    motion.failure = "no match agrees with either model";
    return motion;
  }
  motion.used_homography = homography_score / (homography_score + essential_score) > kHomographyScoreRatio;
  TwoViewSolution solution = motion.used_homography
                                 ? motionFromHomography(homography, homography_mask, camera_matrix, p1, p2)
                                 : motionFromEssential(essential, essential_mask, camera, p1, p2, bounds.essential_px);
  if (static_cast<int>(solution.inliers.in_front.size()) < kMinMatches) {
    motion.failure = std::string(motion.used_homography ? "homography" : "essential matrix") + " leaves " +
                     std::to_string(solution.inliers.in_front.size()) + " matches in front of both cameras, " +
                     std::to_string(kMinMatches) + " needed";
    return motion;
  }
  const auto pose_2_in_1 = poseOfSecondInFirst(solution.rotation, solution.translation);
  if (!pose_2_in_1) {
    motion.failure = "the recovered motion has no translation";
    return motion;
  }
  motion.ok = true;
  motion.pose_2_in_1 = *pose_2_in_1;
  motion.median_parallax_deg = median(solution.inliers.parallax_deg);
  motion.inliers = std::move(solution.inliers.in_front);
  return motion;
}

}  // namespace

RelativeMotion estimateRelativeMotion2d2d(const std::vector<Eigen::Vector2d>& pixels1,
                                          const std::vector<Eigen::Vector2d>& pixels2, const PinholeCamera& camera,
                                          const RelativeMotionOptions& options) {
  RelativeMotion motion;
  if (pixels1.size() != pixels2.size()) {
    motion.failure = "mismatched sizes: " + std::to_string(pixels1.size()) + " and " + std::to_string(pixels2.size());
    return motion;
  }
  if (const auto problem = detail::cameraProblem(camera)) {
    motion.failure = *problem;
    return motion;
  }
  if (!(options.pixel_sigma > 0 && std::isfinite(options.pixel_sigma))) {
    motion.failure = "invalid options: pixel_sigma must be positive";
    return motion;
  }
  const NoiseBounds bounds(options.pixel_sigma);
  std::vector<int> valid;  // input index of each point passed to OpenCV
  std::vector<cv::Point2d> p1, p2;
  for (std::size_t i = 0; i < pixels1.size(); ++i) {
    if (!pixels1[i].allFinite() || !pixels2[i].allFinite()) continue;
    valid.push_back(static_cast<int>(i));
    p1.emplace_back(pixels1[i].x(), pixels1[i].y());
    p2.emplace_back(pixels2[i].x(), pixels2[i].y());
  }
  if (static_cast<int>(valid.size()) < kMinMatches) {
    motion.failure =
        "too few matches: " + std::to_string(valid.size()) + " finite, " + std::to_string(kMinMatches) + " needed";
    return motion;
  }

  try {
    motion = fitTwoViewMotion(p1, p2, camera, bounds);
  } catch (const cv::Exception& e) {
    motion.failure = std::string("OpenCV failed on degenerate matches: ") + e.what();
  }
  for (int& index : motion.inliers) index = valid[index];
  return motion;
}

}  // namespace weighted_icp::frontend
