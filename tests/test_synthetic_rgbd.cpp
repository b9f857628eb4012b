// The synthetic RGB-D sequence: determinism, depth against an independent ray
// caster of the published scene, consistency of texture across views, the
// moving object, dim lighting, features, the TUM files and the tool.

#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "test_support.h"
#include "tool_runner.h"
#include "weighted_icp/io/camera.h"
#include "weighted_icp/io/tum_sequence.h"
#include "weighted_icp/simulation/rgbd_sequence.h"
#include "weighted_icp/simulation/tum_export.h"

namespace {

using namespace weighted_icp;
namespace fs = std::filesystem;
using weighted_icp::testing::binaryDir;
using weighted_icp::testing::scratchDir;

/// The frame's depth as the simulated sensor stored it (16-bit, depth_factor
/// units): the metric depth converts back exactly, and the quantisation the
/// tests check is clearest there.
cv::Mat rawDepth(const simulation::SyntheticRgbdFrame& frame) {
  return depthToRaw(frame.rgbd.depth, simulation::syntheticRgbdCamera().depth_factor);
}

constexpr std::uint64_t kSeed = 7;

simulation::SyntheticRgbdOptions exactOptions(bool moving_object) {
  simulation::SyntheticRgbdOptions options;
  options.seed = kSeed;
  options.depth_noise = false;
  options.moving_object = moving_object;
  return options;
}

// Building a sequence draws its textures (a fraction of a second): share them.
const simulation::SyntheticRgbdSequence& exactStatic() {
  static const simulation::SyntheticRgbdSequence sequence(exactOptions(false));
  return sequence;
}
const simulation::SyntheticRgbdSequence& exactWithObject() {
  static const simulation::SyntheticRgbdSequence sequence(exactOptions(true));
  return sequence;
}

cv::Mat gray(const cv::Mat& color) {
  cv::Mat result;
  cv::cvtColor(color, result, cv::COLOR_BGR2GRAY);
  return result;
}

double meanAbsoluteDifference(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat difference;
  cv::absdiff(a, b, difference);
  return cv::mean(difference.reshape(1))[0];
}

// --- An independent ray caster of the scene the sequence publishes.

struct RayHit {
  double t = std::numeric_limits<double>::infinity();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
};

void castAgainstBox(const simulation::SceneBox& box, const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                    RayHit& nearest) {
  const Eigen::Matrix3d box_to_world = Eigen::AngleAxisd(box.yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Vector3d o = box_to_world.transpose() * (origin - box.center);
  const Eigen::Vector3d d = box_to_world.transpose() * direction;
  const Eigen::Vector3d half = box.size / 2.0;
  // Each face plane in turn: the entry point is the nearest one within the face.
  for (int axis = 0; axis < 3; ++axis) {
    for (const double side : {-1.0, 1.0}) {
      if (d[axis] == 0.0) continue;
      const double t = (side * half[axis] - o[axis]) / d[axis];
      if (t <= 0.0 || t >= nearest.t) continue;
      const Eigen::Vector3d p = o + t * d;
      bool within = true;
      for (int other = 0; other < 3; ++other)
        if (other != axis && std::abs(p[other]) > half[other]) within = false;
      if (!within || side * d[axis] >= 0.0) continue;  // outside the face, or leaving the box
      nearest.t = t;
      nearest.normal = box_to_world.col(axis) * side;
    }
  }
}

RayHit castRay(const simulation::SyntheticRgbdSequence& sequence, std::size_t frame, const Eigen::Vector3d& origin,
               const Eigen::Vector3d& direction) {
  RayHit nearest;
  const Eigen::Vector3d room = sequence.roomSize();
  const Eigen::Vector3d low(-room.x() / 2, -room.y() / 2, 0.0), high(room.x() / 2, room.y() / 2, room.z());
  for (int axis = 0; axis < 3; ++axis) {
    if (direction[axis] == 0.0) continue;
    const double wall = direction[axis] > 0.0 ? high[axis] : low[axis];
    const double t = (wall - origin[axis]) / direction[axis];
    if (t > 0.0 && t < nearest.t) {
      nearest.t = t;
      nearest.normal = Eigen::Vector3d::Zero();
      nearest.normal[axis] = direction[axis] > 0.0 ? -1.0 : 1.0;
    }
  }
  for (const simulation::SceneBox& box : sequence.furniture()) castAgainstBox(box, origin, direction, nearest);
  if (const auto object = sequence.movingObject(frame)) castAgainstBox(*object, origin, direction, nearest);
  return nearest;
}

/// Signed distance-like measure to a box's surface: 0 on it.
double boxSurfaceOffset(const simulation::SceneBox& box, const Eigen::Vector3d& point) {
  const Eigen::Vector3d local =
      Eigen::AngleAxisd(-box.yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix() * (point - box.center);
  return (local.cwiseAbs() - box.size / 2.0).maxCoeff();
}

/// The frames (sampled every `step`) in which the moving object is rendered.
std::vector<std::size_t> framesWithObject(std::size_t step) {
  std::vector<std::size_t> frames;
  for (std::size_t i = 0; i < exactWithObject().size(); i += step)
    if (cv::countNonZero(exactWithObject().frame(i).moving_object_mask) > 0) frames.push_back(i);
  return frames;
}

// --- Determinism and options.

TEST(SyntheticRgbd, SameSeedGivesIdenticalFramesAndPoses) {
  const simulation::SyntheticRgbdSequence again(exactOptions(false));
  for (const std::size_t i : {0, 77}) {
    const simulation::SyntheticRgbdFrame first = exactStatic().frame(i), second = again.frame(i);
    EXPECT_EQ(cv::norm(first.rgbd.color, second.rgbd.color, cv::NORM_INF), 0.0) << "frame " << i;
    EXPECT_EQ(cv::norm(rawDepth(first), rawDepth(second), cv::NORM_INF), 0.0) << "frame " << i;
    EXPECT_TRUE(first.camera_to_world.matrix() == second.camera_to_world.matrix()) << "frame " << i;
    EXPECT_EQ(first.rgbd.timestamp, second.rgbd.timestamp);
  }
}

TEST(SyntheticRgbd, RenderingDoesNotDependOnTheThreadCount) {
  const int threads = cv::getNumThreads();
  cv::setNumThreads(1);
  const simulation::SyntheticRgbdSequence single_threaded(exactOptions(false));
  const simulation::SyntheticRgbdFrame single = single_threaded.frame(12);
  cv::setNumThreads(threads);
  const simulation::SyntheticRgbdFrame parallel = exactStatic().frame(12);
  EXPECT_EQ(cv::norm(single.rgbd.color, parallel.rgbd.color, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(rawDepth(single), rawDepth(parallel), cv::NORM_INF), 0.0);
}

TEST(SyntheticRgbd, DifferentSeedGivesDifferentTexture) {
  simulation::SyntheticRgbdOptions options = exactOptions(false);
  options.seed = kSeed + 1;
  const simulation::SyntheticRgbdSequence other(options);
  // Grey levels of two unrelated textures differ by tens on average; noise alone by about 1.
  EXPECT_GT(meanAbsoluteDifference(exactStatic().frame(0).rgbd.color, other.frame(0).rgbd.color), 15.0);
}

TEST(SyntheticRgbd, DepthNoiseIsDeterministicAndUnbiased) {
  const simulation::SyntheticRgbdSequence noisy(simulation::SyntheticRgbdOptions{});
  const simulation::SyntheticRgbdSequence noisy_again(simulation::SyntheticRgbdOptions{});
  EXPECT_EQ(cv::norm(rawDepth(noisy.frame(3)), rawDepth(noisy_again.frame(3)), cv::NORM_INF), 0.0);
  simulation::SyntheticRgbdOptions exact;
  exact.depth_noise = false;
  const simulation::SyntheticRgbdSequence clean(exact);
  const cv::Mat noisy_depth = rawDepth(noisy.frame(3)), clean_depth = rawDepth(clean.frame(3));
  cv::Mat noisy_metres, clean_metres;
  noisy_depth.convertTo(noisy_metres, CV_64F, 1.0 / 5000.0);
  clean_depth.convertTo(clean_metres, CV_64F, 1.0 / 5000.0);
  // Noise of sigma 0.0015 z^2 plus the disparity step: millimetres to centimetres
  // at 1.5-3 m, but never a bias of more than a few millimetres on average.
  const cv::Mat valid = (noisy_depth > 0) & (clean_depth > 0);
  const cv::Mat error = noisy_metres - clean_metres;
  cv::Scalar mean, deviation;
  cv::meanStdDev(error, mean, deviation, valid);
  EXPECT_GT(deviation[0], 0.002);
  EXPECT_LT(deviation[0], 0.03);
  EXPECT_LT(std::abs(mean[0]), 0.003);
}

TEST(SyntheticRgbd, DepthDistortionGrowsWithTheSquaredRadius) {
  simulation::SyntheticRgbdOptions exact;
  exact.depth_noise = false;
  simulation::SyntheticRgbdOptions distorted = exact;
  distorted.depth_distortion = 0.05;
  const cv::Mat clean = rawDepth(simulation::SyntheticRgbdSequence(exact).frame(5));
  const cv::Mat bent = rawDepth(simulation::SyntheticRgbdSequence(distorted).frame(5));
  const PinholeCamera& camera = exact.camera;
  std::size_t checked = 0;
  for (int v = 0; v < camera.height; v += 37) {
    for (int u = 0; u < camera.width; u += 41) {
      const double z = clean.at<std::uint16_t>(v, u), z_bent = bent.at<std::uint16_t>(v, u);
      if (z == 0.0 || z_bent == 0.0) continue;
      const double r2 = std::pow((u - camera.cx) / camera.fx, 2) + std::pow((v - camera.cy) / camera.fy, 2);
      // The stored values are rounded to 1 / depth_factor: half a step each.
      EXPECT_NEAR(z_bent, z * (1.0 + 0.05 * r2), 1.1) << "pixel " << u << ", " << v;
      ++checked;
    }
  }
  EXPECT_GT(checked, 100u);
}

TEST(SyntheticRgbd, RejectsBadOptions) {
  const auto rejects = [](auto change) {
    simulation::SyntheticRgbdOptions options;
    change(options);
    EXPECT_THROW(simulation::SyntheticRgbdSequence{options}, std::invalid_argument);
  };
  rejects([](simulation::SyntheticRgbdOptions& o) { o.frames = 0; });
  rejects([](simulation::SyntheticRgbdOptions& o) { o.fps = 0.0; });
  rejects([](simulation::SyntheticRgbdOptions& o) { o.depth_noise_coefficient = -0.001; });
  rejects([](simulation::SyntheticRgbdOptions& o) { o.depth_distortion = 0.2; });
  rejects([](simulation::SyntheticRgbdOptions& o) { o.camera.distortion[0] = 0.1; });
  rejects([](simulation::SyntheticRgbdOptions& o) { o.camera.depth_factor = 0.0; });
  rejects([](simulation::SyntheticRgbdOptions& o) { o.max_depth = o.min_depth; });
  EXPECT_THROW(exactStatic().frame(exactStatic().size()), std::out_of_range);
}

// --- Geometry.

TEST(SyntheticRgbd, CameraMovesLikeAHandHeldCamera) {
  const simulation::SyntheticRgbdSequence& sequence = exactStatic();
  double path_length = 0.0;
  for (std::size_t i = 1; i < sequence.size(); ++i) {
    const Eigen::Isometry3d step = sequence.cameraToWorld(i - 1).inverse() * sequence.cameraToWorld(i);
    const double degrees = Eigen::AngleAxisd(step.linear()).angle() * 180.0 / M_PI;
    EXPECT_LT(step.translation().norm(), 0.02) << "frame " << i;
    EXPECT_LT(degrees, 1.2) << "frame " << i;
    path_length += step.translation().norm();
    EXPECT_NEAR(sequence.timestamp(i) - sequence.timestamp(i - 1), 1.0 / 30.0, 1e-12);
  }
  EXPECT_GT(path_length, 0.8);  // it does travel: about 1 cm per frame
  EXPECT_TRUE(sequence.frame(40).camera_to_world.matrix() == sequence.cameraToWorld(40).matrix());
}

TEST(SyntheticRgbd, DepthEqualsTheDistanceAlongTheRayToTheScene) {
  const simulation::SyntheticRgbdSequence& sequence = exactWithObject();
  const PinholeCamera& camera = sequence.options().camera;
  const double cos_max_incidence = std::cos(sequence.options().max_incidence_deg * M_PI / 180.0);
  std::vector<std::size_t> frames = {0, 100};
  const std::vector<std::size_t> with_object = framesWithObject(10);
  ASSERT_FALSE(with_object.empty());
  frames.push_back(with_object.front());
  for (const std::size_t i : frames) {
    const simulation::SyntheticRgbdFrame frame = sequence.frame(i);
    const cv::Mat raw = rawDepth(frame);
    const Eigen::Vector3d origin = frame.camera_to_world.translation();
    std::size_t checked = 0, measurable = 0, wrong = 0;
    for (int v = 0; v < camera.height; v += 4) {
      for (int u = 0; u < camera.width; u += 4) {
        // A ray whose camera z is 1, so its parameter at the hit is the depth.
        const Eigen::Vector3d direction = frame.camera_to_world.linear() * camera.backProject(u, v, 1.0);
        const RayHit hit = castRay(sequence, i, origin, direction);
        const bool in_range = hit.t >= sequence.options().min_depth && hit.t <= sequence.options().max_depth;
        const bool facing = std::abs(hit.normal.dot(direction)) / direction.norm() >= cos_max_incidence;
        const std::uint16_t stored = raw.at<std::uint16_t>(v, u);
        ++checked;
        measurable += in_range && facing;
        // Exact up to the depth image's resolution; 0 where the sensor could not measure.
        const bool right = in_range && facing
                               ? std::abs(stored / camera.depth_factor - hit.t) <= 0.5 / camera.depth_factor + 1e-9
                               : stored == 0;
        if (!right && ++wrong <= 5)
          ADD_FAILURE() << "frame " << i << " pixel " << u << ' ' << v << ": depth " << stored / camera.depth_factor
                        << ", true " << hit.t << (in_range && facing ? "" : " (not measurable)");
      }
    }
    EXPECT_EQ(wrong, 0u) << "frame " << i << ", of " << checked << " pixels";
    EXPECT_GT(measurable, checked * 9 / 10) << "frame " << i << ": a room 1.5-4 m away is mostly measurable";
  }
}

TEST(SyntheticRgbd, BackProjectedPixelsLieOnTheRoomsSurfaces) {
  const simulation::SyntheticRgbdSequence& sequence = exactWithObject();
  const PinholeCamera& camera = sequence.options().camera;
  const Eigen::Vector3d room = sequence.roomSize();
  std::size_t on_furniture = 0;
  for (const std::size_t i : {20, 60, 140}) {
    const simulation::SyntheticRgbdFrame frame = sequence.frame(i);
    const cv::Mat raw = rawDepth(frame);
    for (int v = 3; v < camera.height; v += 12) {
      for (int u = 5; u < camera.width; u += 12) {
        const std::uint16_t stored = raw.at<std::uint16_t>(v, u);
        if (stored == 0) continue;
        const Eigen::Vector3d point = frame.camera_to_world * camera.backProject(u, v, stored / camera.depth_factor);
        // On a wall, the floor or the ceiling, or on a box: within the depth resolution (and its slant).
        double offset =
            std::min({std::abs(std::abs(point.x()) - room.x() / 2), std::abs(std::abs(point.y()) - room.y() / 2),
                      std::abs(point.z()), std::abs(point.z() - room.z())});
        const double on_room = offset;
        for (const simulation::SceneBox& box : sequence.furniture())
          offset = std::min(offset, std::abs(boxSurfaceOffset(box, point)));
        if (const auto object = sequence.movingObject(i))
          offset = std::min(offset, std::abs(boxSurfaceOffset(*object, point)));
        EXPECT_LT(offset, 0.0005) << "frame " << i << " pixel " << u << ' ' << v << " -> " << point.transpose();
        if (offset < on_room) ++on_furniture;
      }
    }
  }
  EXPECT_GT(on_furniture, 0u) << "the check needs points on furniture, not only on walls";
}

double normalisedCrossCorrelation(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat a_centred = a - cv::mean(a)[0], b_centred = b - cv::mean(b)[0];
  return a_centred.dot(b_centred) / std::sqrt(a_centred.dot(a_centred) * b_centred.dot(b_centred));
}

TEST(SyntheticRgbd, TexturedPointsLookTheSameFromTwoViews) {
  const simulation::SyntheticRgbdSequence& sequence = exactStatic();
  const PinholeCamera& camera = sequence.options().camera;
  const std::size_t first_index = 30, second_index = 42;  // 12 frames: some 10 cm and 7 deg apart
  const simulation::SyntheticRgbdFrame first = sequence.frame(first_index), second = sequence.frame(second_index);
  const cv::Mat first_raw = rawDepth(first), second_raw = rawDepth(second);
  cv::Mat first_gray, second_gray;
  gray(first.rgbd.color).convertTo(first_gray, CV_32F);
  gray(second.rgbd.color).convertTo(second_gray, CV_32F);
  const Eigen::Isometry3d second_from_first = second.camera_to_world.inverse() * first.camera_to_world;
  const cv::Size patch(11, 11);
  std::vector<double> matched, shifted;
  for (int v = 20; v < camera.height - 20; v += 16) {
    for (int u = 20; u < camera.width - 20; u += 16) {
      const std::uint16_t stored = first_raw.at<std::uint16_t>(v, u);
      if (stored == 0) continue;
      const cv::Mat first_patch = first_gray(cv::Rect(u - 5, v - 5, 11, 11));
      cv::Scalar mean, deviation;
      cv::meanStdDev(first_patch, mean, deviation);
      if (deviation[0] < 10.0) continue;  // a flat patch says nothing about alignment
      const Eigen::Vector3d in_second = second_from_first * camera.backProject(u, v, stored / camera.depth_factor);
      const Eigen::Vector2d pixel = camera.project(in_second);
      if (pixel.x() < 20 || pixel.y() < 20 || pixel.x() > camera.width - 20 || pixel.y() > camera.height - 20) continue;
      // Skip points hidden in the second view.
      const double seen_depth =
          second_raw.at<std::uint16_t>(cvRound(pixel.y()), cvRound(pixel.x())) / camera.depth_factor;
      if (std::abs(seen_depth - in_second.z()) > 0.01) continue;
      cv::Mat second_patch, wrong_patch;
      cv::getRectSubPix(second_gray, patch, cv::Point2f(pixel.x(), pixel.y()), second_patch);
      cv::getRectSubPix(second_gray, patch, cv::Point2f(pixel.x() + 7, pixel.y() + 4), wrong_patch);
      matched.push_back(normalisedCrossCorrelation(first_patch, second_patch));
      shifted.push_back(normalisedCrossCorrelation(first_patch, wrong_patch));
    }
  }
  ASSERT_GT(matched.size(), 100u);
  const auto fraction_above = [](const std::vector<double>& values, double threshold) {
    return static_cast<double>(std::count_if(values.begin(), values.end(), [&](double x) { return x > threshold; })) /
           values.size();
  };
  EXPECT_GT(fraction_above(matched, 0.8), 0.95);
  EXPECT_LT(fraction_above(shifted, 0.8), 0.2);  // the check can fail: a wrong pixel does not match
}

// --- The moving object.

TEST(SyntheticRgbd, MovingObjectComesAndGoesAndIsNearerThanTheRoom) {
  std::size_t frames_with = 0, frames_without = 0;
  int largest = 0;
  const int pixels = exactWithObject().options().camera.width * exactWithObject().options().camera.height;
  for (std::size_t i = 0; i < exactWithObject().size(); i += 5) {
    const simulation::SyntheticRgbdFrame with = exactWithObject().frame(i);
    const int covered = cv::countNonZero(with.moving_object_mask);
    largest = std::max(largest, covered);
    if (covered == 0) {
      ++frames_without;
      continue;
    }
    ++frames_with;
    const simulation::SyntheticRgbdFrame without = exactStatic().frame(i);
    EXPECT_EQ(cv::countNonZero(without.moving_object_mask), 0);
    // Where the object is not, nothing changed; where it is, it hides a farther surface.
    const cv::Mat elsewhere = with.moving_object_mask == 0;
    const cv::Mat with_raw = rawDepth(with), without_raw = rawDepth(without);
    EXPECT_EQ(cv::norm(with_raw, without_raw, cv::NORM_INF, elsewhere), 0.0) << "frame " << i;
    EXPECT_EQ(cv::norm(with.rgbd.color, without.rgbd.color, cv::NORM_INF, elsewhere), 0.0) << "frame " << i;
    std::size_t nearer = 0, compared = 0;  // hides means nearer, by the object's own depth
    for (int v = 0; v < with_raw.rows; ++v)
      for (int u = 0; u < with_raw.cols; ++u) {
        const std::uint16_t object_depth = with_raw.at<std::uint16_t>(v, u),
                            room_depth = without_raw.at<std::uint16_t>(v, u);
        if (with.moving_object_mask.at<std::uint8_t>(v, u) == 0 || object_depth == 0 || room_depth == 0) continue;
        ++compared;
        if (object_depth < room_depth) ++nearer;
      }
    EXPECT_GT(compared, 0u) << "frame " << i;
    EXPECT_EQ(nearer, compared) << "frame " << i;
  }
  EXPECT_GT(frames_with, 3u);
  EXPECT_GT(frames_without, 3u);
  EXPECT_GT(largest, pixels / 20);  // a real occluder, not a speck
  EXPECT_LT(largest, pixels / 3);   // but not the whole view

  for (std::size_t i = 0; i < exactStatic().size(); i += 5) EXPECT_FALSE(exactStatic().movingObject(i).has_value());
}

// --- Images for a feature tracker.

TEST(SyntheticRgbd, NormalFramesHavePlentyOfCorners) {
  const simulation::SyntheticRgbdSequence sequence(simulation::SyntheticRgbdOptions{});
  for (const std::size_t i : {0, 50, 100, 149}) {
    std::vector<cv::Point2f> corners;
    cv::goodFeaturesToTrack(gray(sequence.frame(i).rgbd.color), corners, 500, 0.01, 10);
    EXPECT_GE(corners.size(), 300u) << "frame " << i;
  }
}

TEST(SyntheticRgbd, DimLightingIsDarkerFlatterAndDefeatsFixedThresholds) {
  simulation::SyntheticRgbdOptions dim_options = exactOptions(false);
  dim_options.dim_lighting = true;
  const simulation::SyntheticRgbdSequence dim_sequence(dim_options);
  for (const std::size_t i : {10, 110}) {
    const cv::Mat normal = gray(exactStatic().frame(i).rgbd.color), dim = gray(dim_sequence.frame(i).rgbd.color);
    cv::Scalar normal_mean, normal_contrast, dim_mean, dim_contrast;
    cv::meanStdDev(normal, normal_mean, normal_contrast);
    cv::meanStdDev(dim, dim_mean, dim_contrast);
    EXPECT_LT(dim_mean[0], normal_mean[0] / 2) << "frame " << i;
    EXPECT_LT(dim_contrast[0], normal_contrast[0] / 2) << "frame " << i;

    // FAST with ORB's threshold (20 grey levels) starves; CLAHE brings it back.
    const auto fast_corners = [](const cv::Mat& image) {
      std::vector<cv::KeyPoint> keypoints;
      cv::FAST(image, keypoints, 20);
      return keypoints.size();
    };
    cv::Mat equalised;
    cv::createCLAHE(2.0, cv::Size(8, 8))->apply(dim, equalised);
    EXPECT_LT(fast_corners(dim) * 4, fast_corners(normal)) << "frame " << i;
    EXPECT_GT(fast_corners(equalised), fast_corners(dim) * 4) << "frame " << i;
  }
}

// --- The TUM layout.

std::vector<std::vector<std::string>> readListFile(const fs::path& path) {
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << path;
  std::vector<std::vector<std::string>> rows;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::vector<std::string> row;
    for (std::string field; fields >> field;) row.push_back(field);
    rows.push_back(row);
  }
  return rows;
}

simulation::SyntheticRgbdSequence shortSequence() {
  simulation::SyntheticRgbdOptions options;
  options.seed = kSeed;
  options.frames = 4;
  return simulation::SyntheticRgbdSequence(options);
}

TEST(SyntheticRgbd, WritesTheTumLayout) {
  const fs::path dir = scratchDir("synthetic_rgbd_write") / "sequence";
  const simulation::SyntheticRgbdSequence sequence = shortSequence();
  std::vector<std::size_t> reported;
  simulation::writeTumSequence(sequence, dir.string(), false, [&](std::size_t i) { reported.push_back(i); });
  EXPECT_EQ(reported, (std::vector<std::size_t>{0, 1, 2, 3}));
  // Nothing left beside it: the temporary folder became `dir`.
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.parent_path()), fs::directory_iterator()), 1);

  const auto rgb = readListFile(dir / "rgb.txt"), depth = readListFile(dir / "depth.txt"),
             truth = readListFile(dir / "groundtruth.txt");
  ASSERT_EQ(rgb.size(), 4u);
  ASSERT_EQ(depth.size(), 4u);
  ASSERT_EQ(truth.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) {
    ASSERT_EQ(rgb[i].size(), 2u);
    ASSERT_EQ(depth[i].size(), 2u);
    ASSERT_EQ(truth[i].size(), 8u);
    EXPECT_EQ(rgb[i][0], depth[i][0]);
    EXPECT_EQ(std::stod(rgb[i][0]), std::stod(truth[i][0]));  // the same time, written by io's trajectory writer
    EXPECT_NEAR(std::stod(rgb[i][0]), sequence.timestamp(i), 1e-6);

    const simulation::SyntheticRgbdFrame frame = sequence.frame(i);
    const cv::Mat color = cv::imread((dir / rgb[i][1]).string(), cv::IMREAD_UNCHANGED);
    const cv::Mat depth_image = cv::imread((dir / depth[i][1]).string(), cv::IMREAD_UNCHANGED);
    ASSERT_EQ(color.type(), CV_8UC3);
    ASSERT_EQ(depth_image.type(), CV_16UC1);
    EXPECT_EQ(color.size(), cv::Size(640, 480));
    EXPECT_EQ(depth_image.size(), cv::Size(640, 480));
    EXPECT_EQ(cv::norm(color, frame.rgbd.color, cv::NORM_INF), 0.0);  // PNG is lossless
    EXPECT_EQ(cv::norm(depth_image, rawDepth(frame), cv::NORM_INF), 0.0);

    const Eigen::Vector3d translation(std::stod(truth[i][1]), std::stod(truth[i][2]), std::stod(truth[i][3]));
    const Eigen::Quaterniond rotation(std::stod(truth[i][7]), std::stod(truth[i][4]), std::stod(truth[i][5]),
                                      std::stod(truth[i][6]));  // TUM: x y z w; Eigen: w x y z
    EXPECT_NEAR(rotation.norm(), 1.0, 1e-12);
    EXPECT_EQ(translation, frame.camera_to_world.translation());
    EXPECT_TRUE(rotation.toRotationMatrix().isApprox(frame.camera_to_world.linear(), 1e-12));
  }

  // The camera is written with it (fr1's intrinsics without fr1's lens distortion: not the fr1 preset).
  const PinholeCamera camera = io::loadCamera((dir / "camera.yaml").string());
  EXPECT_EQ(camera.fx, sequence.options().camera.fx);
  EXPECT_EQ(camera.cy, sequence.options().camera.cy);
  EXPECT_EQ(camera.depth_factor, sequence.options().camera.depth_factor);
  for (int k = 0; k < 5; ++k) EXPECT_EQ(camera.distortion[k], sequence.options().camera.distortion[k]) << k;

  // The project's own reader agrees.
  const io::TumSequence read = io::TumSequence::open(dir.string());
  ASSERT_EQ(read.size(), 4u);
  ASSERT_TRUE(read.hasGroundTruth());
  const auto pose = read.groundTruthAt(read.frame(2).rgb_timestamp);
  ASSERT_TRUE(pose.has_value());
  EXPECT_TRUE(pose->isApprox(sequence.cameraToWorld(2), 1e-9));
}

TEST(SyntheticRgbd, RefusesANonEmptyFolderUnlessToldToOverwrite) {
  const fs::path dir = scratchDir("synthetic_rgbd_refuse") / "sequence";
  fs::create_directories(dir);
  simulation::writeTumSequence(shortSequence(), dir.string());  // an empty folder is fine
  ASSERT_TRUE(fs::exists(dir / "rgb.txt"));
  std::ofstream(dir / "keep.txt") << "mine\n";

  EXPECT_THROW(simulation::writeTumSequence(shortSequence(), dir.string()), std::runtime_error);
  EXPECT_TRUE(fs::exists(dir / "keep.txt"));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.parent_path()), fs::directory_iterator()), 1);

  simulation::writeTumSequence(shortSequence(), dir.string(), true);
  EXPECT_FALSE(fs::exists(dir / "keep.txt"));
  EXPECT_TRUE(fs::exists(dir / "groundtruth.txt"));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.parent_path()), fs::directory_iterator()), 1);

  const fs::path file = dir.parent_path() / "a_file";
  std::ofstream(file) << "x";
  EXPECT_THROW(simulation::writeTumSequence(shortSequence(), file.string(), true), std::runtime_error);
}

// --- The tool, run as a user would.

using weighted_icp::testing::ToolRun;

ToolRun runTool(const std::string& arguments, const fs::path& scratch) {
  return weighted_icp::testing::runBuiltTool("wicp_synthetic_rgbd", arguments, scratch);
}

TEST(SyntheticRgbdTool, WritesASequenceAndRejectsBadOptions) {
  const fs::path tool = binaryDir() / "examples" / "wicp_synthetic_rgbd";
  if (!fs::exists(tool)) GTEST_SKIP() << "build the wicp_synthetic_rgbd target first (" << tool << ")";
  const fs::path scratch = scratchDir("synthetic_rgbd_tool");
  const std::string out = "'" + (scratch / "sequence").string() + "'";

  ToolRun run = runTool("--out " + out + " --frames 3 --seed 5 --moving-object --dim --no-depth-noise", scratch);
  EXPECT_EQ(run.status, 0) << run.err;
  EXPECT_EQ(readListFile(scratch / "sequence" / "rgb.txt").size(), 3u);

  run = runTool("--out " + out + " --frames 2", scratch);  // exists: refused
  EXPECT_EQ(run.status, 1);
  EXPECT_NE(run.err.find("not empty"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("(--overwrite replaces it)"), std::string::npos) << run.err;
  EXPECT_EQ(readListFile(scratch / "sequence" / "rgb.txt").size(), 3u);
  run = runTool("--out " + out + " --frames 2 --overwrite", scratch);
  EXPECT_EQ(run.status, 0) << run.err;
  EXPECT_EQ(readListFile(scratch / "sequence" / "rgb.txt").size(), 2u);

  const std::string fresh = "'" + (scratch / "fresh").string() + "'";
  for (const std::string& bad :
       {std::string("--frames 0"), std::string("--frames=-3"), std::string("--depth-noise-coefficient -0.01")}) {
    run = runTool("--out " + fresh + ' ' + bad, scratch);
    EXPECT_EQ(run.status, 2) << bad;  // a bad command line, refused while parsing
    EXPECT_NE(run.err.find(bad.substr(0, bad.find_first_of(" ="))), std::string::npos) << bad << ": " << run.err;
    EXPECT_FALSE(fs::exists(scratch / "fresh")) << bad;
  }
  run = runTool("--frames 2", scratch);  // no --out
  EXPECT_EQ(run.status, 2);
  run = runTool("--out /proc/synthetic_rgbd --frames 1", scratch);  // not writable
  EXPECT_EQ(run.status, 1);
  EXPECT_NE(run.err.find("/proc"), std::string::npos) << run.err;
}

// The scene options wicp_rgbd_slam runs (room, loop, texture) render the same scene to disk, so that a loop
// sequence can be turned into a variant (wicp_make_variant) and run from its folder.
TEST(SyntheticRgbdTool, RendersTheSceneOptionsWicpRgbdSlamTakes) {
  const fs::path tool = binaryDir() / "examples" / "wicp_synthetic_rgbd";
  if (!fs::exists(tool)) GTEST_SKIP() << "build the wicp_synthetic_rgbd target first (" << tool << ")";
  const fs::path scratch = scratchDir("synthetic_rgbd_tool_scene");
  const std::string out = "'" + (scratch / "room").string() + "'";
  ToolRun run =
      runTool("--out " + out + " --frames 3 --seed 4 --room-scale 2 --frames-per-loop 40 --repeated-texture", scratch);
  ASSERT_EQ(run.status, 0) << run.err;

  simulation::SyntheticRgbdOptions options;
  options.frames = 3;
  options.seed = 4;
  options.room_scale = 2.0;
  options.frames_per_loop = 40.0;
  options.repeated_texture = true;
  const simulation::SyntheticRgbdSequence expected(options);
  options.room_scale = 1.0;
  options.repeated_texture = false;
  const simulation::SyntheticRgbdSequence plain(options);
  const io::TumSequence read = io::TumSequence::open((scratch / "room").string());
  ASSERT_EQ(read.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    const auto pose = read.groundTruthAt(read.frame(i).rgb_timestamp);
    ASSERT_TRUE(pose.has_value());
    EXPECT_TRUE(pose->isApprox(expected.cameraToWorld(i), 1e-9)) << "frame " << i;
  }
  // The options took effect: the stretched path and the tiled texture differ from the plain scene's.
  EXPECT_GT((expected.cameraToWorld(2).translation() - plain.cameraToWorld(2).translation()).norm(), 0.1);
  const cv::Mat color = cv::imread(read.frame(1).rgb_path, cv::IMREAD_UNCHANGED);
  EXPECT_EQ(cv::norm(color, expected.frame(1).rgbd.color, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(color, plain.frame(1).rgbd.color, cv::NORM_L1), 0.0);

  run = runTool("--out '" + (scratch / "bad").string() + "' --room-scale 5", scratch);
  EXPECT_EQ(run.status, 2);
  EXPECT_NE(run.err.find("--room-scale"), std::string::npos) << run.err;
}

}  // namespace
