// The synthetic session must be what it claims: deterministic, its
// observations and covariances consistent with its own noise model, its
// odometry drifting, and its mini-maps alignable.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "landmark_map_expectations.h"
#include "test_support.h"
#include "weighted_icp/io/map_format.h"
#include "weighted_icp/registration/landmark_alignment.h"
#include "weighted_icp/registration/rigid_motion.h"
#include "weighted_icp/simulation/session.h"

namespace weighted_icp {
namespace {

using simulation::SyntheticSession;
using simulation::SyntheticSessionOptions;

/// A third of the default session: its first 80 frames, at the same camera
/// speed, so mini-maps of 40 frames overlap as much as the demo's.
SyntheticSessionOptions reducedOptions(std::uint64_t seed = 7) {
  SyntheticSessionOptions options;
  options.seed = seed;
  options.path_arc_deg *= 80.0 / static_cast<double>(options.num_frames);
  options.num_frames = 80;
  return options;
}

std::string serialized(const LandmarkMap& map) {
  std::ostringstream out;
  io::writeLandmarkMap(map, out);
  return out.str();
}

double pearsonCorrelation(const std::vector<double>& a, const std::vector<double>& b) {
  double mean_a = 0.0, mean_b = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    mean_a += a[i];
    mean_b += b[i];
  }
  mean_a /= static_cast<double>(a.size());
  mean_b /= static_cast<double>(b.size());
  double covariance = 0.0, variance_a = 0.0, variance_b = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    covariance += (a[i] - mean_a) * (b[i] - mean_b);
    variance_a += (a[i] - mean_a) * (a[i] - mean_a);
    variance_b += (b[i] - mean_b) * (b[i] - mean_b);
  }
  return covariance / std::sqrt(variance_a * variance_b);
}

/// Rank of each value (0 = smallest); the values here are continuous, so ties
/// do not occur in practice.
std::vector<double> ranks(const std::vector<double>& values) {
  std::vector<std::size_t> order(values.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return values[a] < values[b]; });
  std::vector<double> rank(values.size());
  for (std::size_t i = 0; i < order.size(); ++i) rank[order[i]] = static_cast<double>(i);
  return rank;
}

TEST(SyntheticSession, IsDeterministicForASeedAndDiffersBetweenSeeds) {
  const SyntheticSession first = simulation::generateSyntheticSession(reducedOptions(7));
  const SyntheticSession again = simulation::generateSyntheticSession(reducedOptions(7));
  const SyntheticSession other = simulation::generateSyntheticSession(reducedOptions(8));
  EXPECT_EQ(serialized(first.estimated), serialized(again.estimated));
  EXPECT_EQ(serialized(first.truth), serialized(again.truth));
  EXPECT_NE(serialized(first.estimated), serialized(other.estimated));
  EXPECT_NE(serialized(first.truth), serialized(other.truth));
}

TEST(SyntheticSession, EstimatedAndTrueMapsShareFramesLandmarksAndObservations) {
  const SyntheticSessionOptions options = reducedOptions();
  const SyntheticSession session = simulation::generateSyntheticSession(options);
  ASSERT_EQ(session.estimated.frames.size(), options.num_frames);
  ASSERT_EQ(session.truth.frames.size(), options.num_frames);
  ASSERT_EQ(session.true_camera_poses.size(), options.num_frames);
  for (FrameId k = 0; k < options.num_frames; ++k) {
    ASSERT_TRUE(session.estimated.frames.count(k)) << "frame " << k;
    EXPECT_TRUE(session.truth.frames.at(k).matrix() == session.true_camera_poses[k].matrix()) << "frame " << k;
  }
  ASSERT_EQ(session.estimated.landmarks.size(), session.truth.landmarks.size());
  ASSERT_GT(session.estimated.landmarks.size(), 0u);
  EXPECT_LE(session.estimated.landmarks.size(), options.num_landmarks);
  const Eigen::Vector3d half_room = options.room_size / 2;
  for (std::size_t i = 0; i < session.truth.landmarks.size(); ++i) {
    const Landmark& estimated = session.estimated.landmarks[i];
    const Landmark& truth = session.truth.landmarks[i];
    ASSERT_EQ(estimated.id, truth.id);
    ASSERT_GE(estimated.observations.size(), 1u) << "landmark " << estimated.id;
    ASSERT_EQ(estimated.observations.size(), truth.observations.size());
    std::set<FrameId> observing_frames;
    for (std::size_t j = 0; j < truth.observations.size(); ++j) {
      EXPECT_EQ(estimated.observations[j].frame_id, truth.observations[j].frame_id);
      EXPECT_EQ(estimated.observations[j].u, truth.observations[j].u);
      EXPECT_EQ(estimated.observations[j].v, truth.observations[j].v);
      EXPECT_TRUE(session.estimated.frames.count(truth.observations[j].frame_id));
      observing_frames.insert(truth.observations[j].frame_id);
    }
    EXPECT_EQ(observing_frames.size(), truth.observations.size())
        << "a frame observes landmark " << truth.id << " twice";
    // On a surface of the room: inside its box, walls and floor included.
    EXPECT_LE(std::abs(truth.position.x()), half_room.x() + 1e-9);
    EXPECT_LE(std::abs(truth.position.y()), half_room.y() + 1e-9);
    EXPECT_GE(truth.position.z(), -1e-9);
    EXPECT_LE(truth.position.z(), options.room_size.z() + 1e-9);
  }
}

TEST(SyntheticSession, ObservationsLieInTheImageAndReprojectWithinPixelNoise) {
  const SyntheticSessionOptions options = reducedOptions();
  const SyntheticSession session = simulation::generateSyntheticSession(options);
  const double sigma = options.pixel_noise_sigma;
  double squared_residuals = 0.0;
  std::size_t residuals = 0;
  for (const Landmark& landmark : session.truth.landmarks) {
    for (const Observation& observation : landmark.observations) {
      EXPECT_TRUE(options.camera.inImage(Eigen::Vector2d(observation.u, observation.v)))
          << "landmark " << landmark.id << " frame " << observation.frame_id;
      const Eigen::Vector3d in_camera = session.truth.frames.at(observation.frame_id).inverse() * landmark.position;
      EXPECT_GE(in_camera.z(), options.min_depth);
      EXPECT_LE(in_camera.z(), options.max_depth);
      const Eigen::Vector2d residual =
          options.camera.project(in_camera) - Eigen::Vector2d(observation.u, observation.v);
      // Gaussian noise beyond 6 sigma has odds ~1e-9 per draw.
      EXPECT_LE(residual.cwiseAbs().maxCoeff(), 6.0 * sigma)
          << "landmark " << landmark.id << " frame " << observation.frame_id;
      squared_residuals += residual.squaredNorm();
      residuals += 2;
    }
  }
  ASSERT_GT(residuals, 1000u);
  // The noise is there, with the configured spread.
  EXPECT_NEAR(std::sqrt(squared_residuals / static_cast<double>(residuals)), sigma, 0.1 * sigma);
}

TEST(SyntheticSession, EstimatedPositionsScatterAroundTheDriftedTruthAsTheirCovarianceSays) {
  const SyntheticSession session = simulation::generateSyntheticSession(reducedOptions());
  // Where the odometry puts the true point, averaged over the observations:
  // the estimate differs from it only by measurement noise, which the
  // covariance describes, so the squared Mahalanobis distances follow a
  // chi-square law with 3 degrees of freedom (mean 3).
  double sum_squared_distances = 0.0;
  std::size_t beyond_999th_percentile = 0;
  const std::size_t count = session.estimated.landmarks.size();
  for (std::size_t i = 0; i < count; ++i) {
    const Landmark& estimated = session.estimated.landmarks[i];
    const Landmark& truth = session.truth.landmarks[i];
    Eigen::Vector3d drifted_truth = Eigen::Vector3d::Zero();
    for (const Observation& observation : estimated.observations)
      drifted_truth += session.estimated.frames.at(observation.frame_id) *
                       (session.truth.frames.at(observation.frame_id).inverse() * truth.position);
    drifted_truth /= static_cast<double>(estimated.observations.size());
    const Eigen::Vector3d error = estimated.position - drifted_truth;
    const double squared_distance = error.dot(estimated.covariance.inverse() * error);
    sum_squared_distances += squared_distance;
    if (squared_distance > 16.27) ++beyond_999th_percentile;
  }
  ASSERT_GT(count, 300u);
  EXPECT_NEAR(sum_squared_distances / static_cast<double>(count), 3.0, 0.4);
  EXPECT_LE(beyond_999th_percentile, count / 100);
}

TEST(SyntheticSession, FartherLandmarksHaveLargerCovariance) {
  const SyntheticSession session = simulation::generateSyntheticSession(reducedOptions());
  std::vector<double> covariance_norms, per_observation_covariance_norms, mean_distances;
  for (const Landmark& landmark : session.estimated.landmarks) {
    const LandmarkMetrics metrics = session.estimated.metrics(landmark);
    covariance_norms.push_back(metrics.covariance.norm());
    per_observation_covariance_norms.push_back(metrics.covariance.norm() *
                                               static_cast<double>(metrics.num_observations));
    mean_distances.push_back(metrics.mean_observation_distance);
  }
  // The weighted rule uses only the order of weights, so ranks are what count;
  // dividing by the observation count scatters them, but distance dominates.
  EXPECT_GT(pearsonCorrelation(ranks(covariance_norms), ranks(mean_distances)), 0.5);
  EXPECT_GT(pearsonCorrelation(covariance_norms, mean_distances), 0.0);
  // Per observation, depth noise (sigma_z ~ z^2) nearly fixes the covariance.
  EXPECT_GT(pearsonCorrelation(per_observation_covariance_norms, mean_distances), 0.8);
}

TEST(SyntheticSession, OdometryDriftGrowsWithFrameIndex) {
  // A random walk: one seed may wander back, the mean over seeds grows.
  constexpr int kSeeds = 8;
  SyntheticSessionOptions options;
  options.num_landmarks = 200;  // the trajectory does not depend on them
  const std::size_t quarter = options.num_frames / 4;
  double first_quarter_error = 0.0, last_quarter_error = 0.0;
  for (int seed = 1; seed <= kSeeds; ++seed) {
    options.seed = static_cast<std::uint64_t>(seed);
    const SyntheticSession session = simulation::generateSyntheticSession(options);
    EXPECT_EQ(translationError(session.estimated.frames.at(0), session.truth.frames.at(0)), 0.0);
    EXPECT_EQ(rotationErrorDeg(session.estimated.frames.at(0), session.truth.frames.at(0)), 0.0);
    for (std::size_t k = 0; k < quarter; ++k) {
      first_quarter_error += translationError(session.estimated.frames.at(k), session.truth.frames.at(k));
      const FrameId late = options.num_frames - 1 - k;
      last_quarter_error += translationError(session.estimated.frames.at(late), session.truth.frames.at(late));
    }
  }
  first_quarter_error /= static_cast<double>(kSeeds * quarter);
  last_quarter_error /= static_cast<double>(kSeeds * quarter);
  EXPECT_GT(last_quarter_error, 0.005);  // metres: measurable
  EXPECT_GT(last_quarter_error, 2.0 * first_quarter_error);
}

TEST(SyntheticSession, WithoutDriftTheOdometryIsTheTruth) {
  SyntheticSessionOptions options = reducedOptions();
  options.drift_rotation_sigma_deg = 0.0;
  options.drift_translation_sigma = 0.0;
  const SyntheticSession session = simulation::generateSyntheticSession(options);
  for (const auto& [id, pose] : session.estimated.frames)
    EXPECT_TRUE(pose.isApprox(session.truth.frames.at(id), 1e-9)) << "frame " << id;
}

TEST(SyntheticSession, WrittenMapReadsBackUnchanged) {
  const SyntheticSession session = simulation::generateSyntheticSession(reducedOptions());
  const auto path = (testing::scratchDir("synthetic_session") / "session.txt").string();
  io::writeLandmarkMap(session.estimated, path);
  const LandmarkMap read = io::readLandmarkMap(path);
  ASSERT_EQ(read.frames.size(), session.estimated.frames.size());
  for (const auto& [id, pose] : session.estimated.frames) {
    ASSERT_TRUE(read.frames.count(id)) << "frame " << id;
    // Stored as a quaternion, so the rotation matrix comes back rounded.
    EXPECT_TRUE(read.frames.at(id).isApprox(pose, 1e-12)) << "frame " << id;
  }
  weighted_icp::testing::expectSameLandmarks(session.estimated, read);
}

TEST(SyntheticSession, RejectsOptionsOutOfRangeNamingThem) {
  const auto expectRejected = [](const std::string& option, const auto& spoil) {
    SyntheticSessionOptions options = reducedOptions();
    spoil(options);
    try {
      simulation::generateSyntheticSession(options);
      ADD_FAILURE() << "accepted a bad " << option;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(option), std::string::npos) << e.what();
    }
  };
  expectRejected("num_frames", [](SyntheticSessionOptions& o) { o.num_frames = 0; });
  expectRejected("num_landmarks", [](SyntheticSessionOptions& o) { o.num_landmarks = 0; });
  expectRejected("room_size", [](SyntheticSessionOptions& o) { o.room_size.x() = 2.0; });
  expectRejected("room_size", [](SyntheticSessionOptions& o) { o.room_size.z() = NAN; });
  expectRejected("camera_height", [](SyntheticSessionOptions& o) { o.camera_height = 0.5; });
  expectRejected("path_radius_fraction", [](SyntheticSessionOptions& o) { o.path_radius_fraction = -0.1; });
  expectRejected("path_arc_deg", [](SyntheticSessionOptions& o) { o.path_arc_deg = INFINITY; });
  expectRejected("camera", [](SyntheticSessionOptions& o) { o.camera.fx = 0.0; });
  expectRejected("camera", [](SyntheticSessionOptions& o) { o.camera.width = 0; });
  expectRejected("camera", [](SyntheticSessionOptions& o) { o.camera.distortion[0] = 0.26; });
  expectRejected("max_depth", [](SyntheticSessionOptions& o) { o.max_depth = o.min_depth; });
  expectRejected("min_depth", [](SyntheticSessionOptions& o) { o.min_depth = 0.0; });
  expectRejected("max_viewing_angle_deg", [](SyntheticSessionOptions& o) { o.max_viewing_angle_deg = 95.0; });
  expectRejected("detection_probability", [](SyntheticSessionOptions& o) { o.detection_probability = 0.0; });
  expectRejected("detection_probability", [](SyntheticSessionOptions& o) { o.detection_probability = 1.5; });
  expectRejected("pixel_noise_sigma", [](SyntheticSessionOptions& o) { o.pixel_noise_sigma = NAN; });
  expectRejected("depth_noise_coefficient", [](SyntheticSessionOptions& o) { o.depth_noise_coefficient = -1.0; });
  expectRejected("drift_rotation_sigma_deg", [](SyntheticSessionOptions& o) { o.drift_rotation_sigma_deg = -1.0; });
  expectRejected("drift_translation_sigma", [](SyntheticSessionOptions& o) { o.drift_translation_sigma = -1.0; });
  expectRejected("look_at", [](SyntheticSessionOptions& o) {
    o.path_radius_fraction = 0.0;  // the camera stays below the point it looks at
    o.look_at = Eigen::Vector3d(0.0, 0.0, 2.5);
  });
}

TEST(SyntheticSession, PlainIcpRecoversAKnownDisplacementBetweenConsecutiveMiniMaps) {
  const SyntheticSessionOptions options = reducedOptions();
  const SyntheticSession session = simulation::generateSyntheticSession(options);
  const std::vector<LandmarkMap> minimaps = session.estimated.splitIntoMiniMaps(options.num_frames / 2);
  ASSERT_EQ(minimaps.size(), 2u);
  const LandmarkMap target = minimaps[0].withMinObservations(2);
  LandmarkMap source = minimaps[1].withMinObservations(2);
  const Displacement displacement = Displacement::parse("0.2 -0.15 0.05 3 -2 15");
  source.transform(displacement.toIsometry());

  AlignmentSettings settings;
  settings.k = 1;
  settings.threads = 1;
  const AlignmentResult result = alignLandmarkMaps(source, target, weightFunction(WeightStrategy::Base), settings);
  const Eigen::Isometry3d estimate(result.transformation);
  const Eigen::Isometry3d truth = displacement.toIsometry().inverse();
  // The displacement itself is 15.4 degrees and 20+ cm: recovering it is no accident.
  ASSERT_GT(rotationErrorDeg(Eigen::Isometry3d::Identity(), truth), 15.0);
  EXPECT_LT(rotationErrorDeg(estimate, truth), 0.5);
  EXPECT_LT(translationError(estimate, truth), 0.03);
}

}  // namespace
}  // namespace weighted_icp
