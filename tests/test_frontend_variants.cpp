// The front end on sequence variants (issue #11): the relative quality gate
// keeps burst frames out of the map on real sequences, and the JPEG and
// millimetre-depth variants a Kinect of another dataset would give track as
// accurately as the originals (ATE below a stated bound), and so does a depth
// camera of another resolution.

#include <algorithm>
#include <iostream>
#include <set>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "test_support.h"
#include "weighted_icp/frontend/slam/rgbd_slam.h"
#include "weighted_icp/io/camera.h"
#include "weighted_icp/io/tum_sequence.h"
#include "weighted_icp/metrics/trajectory_error.h"
#include "weighted_icp/simulation/sequence_variants.h"

namespace {

using namespace weighted_icp;
namespace fs = std::filesystem;

struct VariantRun {
  double ate_m = 0.0;
  std::size_t without_pose = 0;
  std::size_t burst_keyframes = 0;  // degraded frames that became keyframes though tracking could spare them
  std::size_t burst_refused = 0, clean_refused = 0;
  std::size_t burst_fallback = 0;  // degraded frames posed by 2D-2D or dense odometry, not skipped on the prediction
  std::size_t dense = 0;           // frames posed by the dense odometry fallback
  std::size_t keyframes = 0;
  std::size_t lost = 0;  // frames that ended their segment
};

/// Writes the variant of the shared sequence into a scratch folder and tracks it (deterministic), as
/// wicp_rgbd_slam --dataset DIR would: the camera is the variant's camera.yaml.
VariantRun trackVariant(const std::string& sequence, int freiburg, const std::string& kinds,
                        frontend::QualityGateMode mode = frontend::QualityGateMode::Relative,
                        std::size_t max_frames = 0, bool describe_depth_camera = true,
                        simulation::SequenceVariantOptions options = {}) {
  const fs::path dir = weighted_icp::testing::scratchDir("variant") / "out";
  options.kinds = simulation::parseVariantKinds(kinds);
  options.describe_depth_camera = describe_depth_camera;
  simulation::VariantSource source =
      simulation::tumVariantSource((weighted_icp::testing::dataDir() / sequence).string(), tumCamera(freiburg));
  if (max_frames) source.size = std::min(source.size, max_frames);  // the variant is written for these frames only
  simulation::writeSequenceVariant(source, options, dir.string());
  const io::TumSequence variant = io::TumSequence::open(dir.string());
  const PinholeCamera camera = io::loadCamera((dir / "camera.yaml").string());
  std::set<std::size_t> degraded;
  if (fs::exists(dir / "bursts.txt"))
    for (const auto& frame : simulation::readDegradedFrames((dir / "bursts.txt").string()))
      degraded.insert(frame.index);

  frontend::RgbdSlamOptions slam_options;
  slam_options.backend.background_thread = false;
  slam_options.frontend.quality.mode = mode;
  frontend::RgbdSlam slam(camera, slam_options);
  VariantRun run;
  for (std::size_t i = 0; i < variant.size(); ++i) {
    const frontend::TrackingResult& result = slam.process(variant.loadFrame(i, camera)).result;
    const bool bad = degraded.count(i) > 0;
    run.without_pose += !result.hasPose();
    // A degraded keyframe is a failure unless it was kept because it barely tracked.
    run.burst_keyframes +=
        bad && result.keyframe && result.inliers >= slam_options.frontend.quality.min_tracked_to_refuse;
    run.keyframes += result.keyframe;
    run.lost += result.status == frontend::TrackingStatus::Lost;
    (bad ? run.burst_refused : run.clean_refused) += result.refused_by_quality_gate;
    run.dense += result.status == frontend::TrackingStatus::TrackedDense;
    run.burst_fallback += bad && (result.status == frontend::TrackingStatus::TrackedRelative ||
                                  result.status == frontend::TrackingStatus::TrackedDense);
  }
  slam.finish();
  run.ate_m = metrics::computeAte(variant.groundTruth(), slam.trajectory()).translation.rmse;
  std::cout << kinds << " on " << sequence << ": ATE " << run.ate_m * 100 << " cm, " << run.without_pose
            << " frames without pose, " << run.keyframes << " keyframes, " << run.burst_keyframes
            << " of them degraded; refused " << run.burst_refused << " degraded, " << run.clean_refused << " clean\n";
  return run;
}

bool haveData(const char* sequence) { return fs::exists(weighted_icp::testing::dataDir() / sequence / "rgb.txt"); }

TEST(FrontendVariants, JpegColourAndMillimetreDepthTrackBelowOneAndAHalfCentimetres) {
  if (!haveData("tum_fr1_xyz_head")) GTEST_SKIP() << "no " << weighted_icp::testing::dataDir() / "tum_fr1_xyz_head";
  // The held-out Kinect's format: JPEG colour, depth in mm, focal 585 px. The
  // original tracks to 0.54-0.58 cm over draws of the matcher's key bits, the variant to 0.53-0.57 cm; 1.5 cm leaves
  // room for the compression, not for a failure.
  const VariantRun run = trackVariant("tum_fr1_xyz_head", 1, "jpeg,mm-depth,focal");
  EXPECT_EQ(run.without_pose, 0u);
  EXPECT_LT(run.ate_m, 0.015);
}

TEST(FrontendVariants, UnregisteredDepthIsRegisteredWithItsCalibration) {
  if (!haveData("tum_fr3_teddy_head")) GTEST_SKIP() << "no " << weighted_icp::testing::dataDir() / "tum_fr3_teddy_head";
  // The variant's camera.yaml names its depth camera: the front end registers every depth image. First 100 frames:
  // the original tracks to 0.30 cm, the variant with its calibration to 0.37-0.48 cm, without it to 1.07-1.87 cm
  // (eight draws of the matcher's key bits).
  const auto relative = frontend::QualityGateMode::Relative;
  const VariantRun registered = trackVariant("tum_fr3_teddy_head", 3, "unregistered", relative, 100);
  const VariantRun unregistered = trackVariant("tum_fr3_teddy_head", 3, "unregistered", relative, 100, false);
  EXPECT_EQ(registered.without_pose, 0u);
  EXPECT_LT(registered.ate_m, 0.008);
  EXPECT_LT(registered.ate_m, 0.75 * unregistered.ate_m);
}

TEST(FrontendVariants, ADepthCameraOfHalfTheResolutionTracksAsTheFullOne) {
  if (!haveData("tum_fr1_xyz_head")) GTEST_SKIP() << "no " << weighted_icp::testing::dataDir() / "tum_fr1_xyz_head";
  // 320x240 depth 2.5 cm beside 640x480 colour with fr1's lens distortion (an Azure Kinect's or ScanNet's layout).
  // The head's 32 associated frames: the original tracks to 0.55-0.58 cm over four draws of the matcher's key bits,
  // this variant to 0.54-0.56 cm (wicp_rgbd_slam --deterministic --lsh-seed 0-3); 1 cm leaves room for the coarser
  // depth, not for a failure.
  const VariantRun run =
      trackVariant("tum_fr1_xyz_head", 1, "unregistered,depth-resolution", frontend::QualityGateMode::Relative, 100);
  EXPECT_EQ(run.without_pose, 0u);
  EXPECT_LT(run.ate_m, 0.01);
}

// Each image the camera does not describe is refused, naming the frame and the size it should have.
TEST(FrontendVariants, ImagesOfAnotherSizeThanTheCamerasAreRefusedWithTheSizeExpected) {
  PinholeCamera camera = tumCamera(3);
  frontend::RgbdSlamOptions options;
  options.backend.background_thread = false;
  RgbdFrame frame;
  frame.timestamp = 12.5;
  frame.color = cv::Mat(480, 640, CV_8UC3, cv::Scalar(90, 90, 90));
  frame.depth = cv::Mat(240, 320, CV_32F, cv::Scalar(1.0f));
  const auto error = [&](const PinholeCamera& with) {
    frontend::RgbdSlam slam(with, options);
    try {
      slam.process(frame);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string registered = error(camera);  // depth must be the colour image's size
  EXPECT_NE(registered.find("12.5"), std::string::npos) << registered;
  EXPECT_NE(registered.find("colour image's size"), std::string::npos) << registered;
  // A depth camera of its own size: 320x240 is right, the colour image then must be the camera's.
  camera.unregistered_depth = DepthCamera{262.0, 262.0, 159.5, 119.5, {0.025, 0.0, 0.0}, {}, 320, 240};
  EXPECT_EQ(error(camera), "no error");
  frame.depth = cv::Mat(480, 640, CV_32F, cv::Scalar(1.0f));
  const std::string depth_size = error(camera);
  EXPECT_NE(depth_size.find("depth camera's size 320x240, found 640x480"), std::string::npos) << depth_size;
  frame.depth = cv::Mat(240, 320, CV_32F, cv::Scalar(1.0f));
  frame.color = cv::Mat(240, 320, CV_8UC3, cv::Scalar(90, 90, 90));
  const std::string colour_size = error(camera);
  EXPECT_NE(colour_size.find("the colour image is 320x240, the camera's 640x480"), std::string::npos) << colour_size;
}

TEST(FrontendVariants, RelativeGateKeepsBurstFramesOutOfTheMapOnTwoSequences) {
  for (const auto& [sequence, freiburg] :
       {std::pair<const char*, int>{"tum_fr1_xyz_head", 1}, std::pair<const char*, int>{"tum_fr3_teddy_head", 3}}) {
    if (!haveData(sequence)) GTEST_SKIP() << "no " << weighted_icp::testing::dataDir() / sequence;
    const VariantRun run = trackVariant(sequence, freiburg, "burst", frontend::QualityGateMode::Relative, 40);
    EXPECT_EQ(run.without_pose, 0u) << sequence;
    EXPECT_EQ(run.burst_keyframes, 0u) << sequence;
    EXPECT_EQ(run.clean_refused, 0u) << sequence;
  }
}

TEST(FrontendVariants, WhenTheMotionChangesSuddenlyTheLocalMapIsMatchedAgainWithAWideGate) {
  if (!haveData("tum_fr3_teddy_head")) GTEST_SKIP() << "no " << weighted_icp::testing::dataDir() / "tum_fr3_teddy_head";
  // fr3 as a dim Kinect would record it (JPEG, mm depth, focal 585, low light), first 150 frames. Around frame 137
  // the camera turns faster than the constant-velocity prediction: within the 40 px gate 3D-2D found 0-8 matches for
  // ten frames, 2D-2D carried the pose and tracking was lost (6.4 cm). Matched again within the 120 px gate
  // of a frame without motion, every frame tracks. Fragile while PnP's RANSAC drew at most 100 sets: over eight
  // draws of the matcher's key bits 0.8-6.4 cm, five of eight losing a frame where a quarter of the matches were
  // right; with 1000 draws 0.70-1.78 cm, none lost; with a frame that still fails coasting on the prediction
  // instead of a 2D-2D pose 0.74-1.43 cm (2026-11-26, docs/frontend_generalisation.md).
  const VariantRun run =
      trackVariant("tum_fr3_teddy_head", 3, "jpeg,mm-depth,focal,low-light", frontend::QualityGateMode::Relative, 150);
  EXPECT_EQ(run.without_pose, 0u);
  EXPECT_EQ(run.lost, 0u);
  EXPECT_LT(run.ate_m, 0.02);
}

TEST(FrontendVariants, ADegradedFrameThatCannotBeTrackedKeepsThePredictionNotA2d2dPose) {
  if (!haveData("tum_fr3_teddy_head")) GTEST_SKIP() << "no " << weighted_icp::testing::dataDir() / "tum_fr3_teddy_head";
  // fr3 with bursts of blurred, noisy frames, first 100: 3D-2D fails on some burst frames. The 2D-2D fallback, meant
  // for good images without depth, posed two of them 4 and 8 cm off; the gate now refuses them first and they keep
  // the motion model's prediction (burst_fallback == 0 is the check of that). The ATE bound is set on the spread over
  // the descriptor index's random key bits, not on one draw: 0.48-0.99 cm over eight (FLANN's LSH and ours, four
  // seeds each; the clean original: 0.30 cm).
  const VariantRun run = trackVariant("tum_fr3_teddy_head", 3, "burst", frontend::QualityGateMode::Relative, 100);
  EXPECT_EQ(run.without_pose, 0u);
  EXPECT_EQ(run.burst_fallback, 0u);
  EXPECT_GT(run.burst_refused, 0u);
  EXPECT_LT(run.ate_m, 0.012);
}

TEST(FrontendVariants, BlurAndLowLightTogetherAreTrackedByTheDenseFallbackAndItsKeyframes) {
  if (!haveData("tum_fr3_teddy_head")) GTEST_SKIP() << "no " << weighted_icp::testing::dataDir() / "tum_fr3_teddy_head";
  // fr3 with motion blur 15 px and low light (gain 0.2, noise 3), all frames: features fail on dozens of frames.
  // Without the dense fallback about 31 frames were lost a run, 37-50 cm over ten draws of the matcher's key bits;
  // with it but no keyframe from its poses, dense poses chained and drifted, 29-30 cm; with its frames mapped, 5-13.5
  // cm and none lost (2026-11-27, docs/frontend_generalisation.md). The bound is set on that spread.
  simulation::SequenceVariantOptions options;
  options.blur_length_px = 15.0;
  options.low_light_gain = 0.2;
  const VariantRun run =
      trackVariant("tum_fr3_teddy_head", 3, "blur,low-light", frontend::QualityGateMode::Relative, 0, true, options);
  EXPECT_EQ(run.lost, 0u);
  EXPECT_EQ(run.without_pose, 0u);
  EXPECT_GT(run.dense, 0u) << "the variant no longer makes 3D-2D fail: the test checks nothing";
  EXPECT_LT(run.ate_m, 0.2);
}

}  // namespace
