// Sequence variants (issue #11): each kind changes what it says and nothing
// else; the camera, lists and ground truth written with it read the variant back
// consistently; bad options and outputs fail before anything is written.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "test_support.h"
#include "weighted_icp/io/camera.h"
#include "weighted_icp/io/tum_sequence.h"
#include "weighted_icp/simulation/image_degradations.h"
#include "weighted_icp/simulation/sequence_variants.h"

namespace {

using namespace weighted_icp;
using weighted_icp::testing::scratchDir;
namespace fs = std::filesystem;

/// A small sequence made here (160x120, a textured wall at 2 m with a box at
/// 1 m, the camera sliding sideways): fast, and every value known.
simulation::VariantSource smallSynthetic(std::size_t frames = 4) {
  PinholeCamera camera;
  camera.fx = camera.fy = 130.0;
  camera.cx = 79.5;
  camera.cy = 59.5;
  camera.width = 160;
  camera.height = 120;
  camera.depth_factor = 5000.0;
  simulation::VariantSource source;
  source.camera = camera;
  source.size = frames;
  source.description = "test sequence";
  source.load = [camera](std::size_t i) {
    RgbdFrame frame;
    frame.timestamp = 100.0 + 0.05 * static_cast<double>(i);
    frame.color = cv::Mat(camera.height, camera.width, CV_8UC3);
    cv::RNG(static_cast<std::uint64_t>(7 + i)).fill(frame.color, cv::RNG::UNIFORM, 0, 256);
    cv::GaussianBlur(frame.color, frame.color, cv::Size(), 1.5);  // texture, not pixel noise
    frame.depth = cv::Mat(camera.height, camera.width, CV_32F, cv::Scalar(2.0f));
    frame.depth(cv::Rect(40 + static_cast<int>(i), 30, 40, 40)).setTo(1.0f);
    frame.depth.at<float>(5, 5) = 0.0f;  // no reading
    return frame;
  };
  source.depth_timestamp = [](std::size_t i) { return 100.01 + 0.05 * static_cast<double>(i); };
  for (std::size_t i = 0; i < frames; ++i) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation().x() = 0.01 * static_cast<double>(i);
    source.groundtruth.push_back({100.0 + 0.05 * static_cast<double>(i), pose});
  }
  return source;
}

simulation::SequenceVariantOptions kinds(const std::string& names) {
  simulation::SequenceVariantOptions options;
  options.kinds = simulation::parseVariantKinds(names);
  return options;
}

struct Written {
  io::TumSequence sequence;
  PinholeCamera camera;
};

Written writeAndOpen(const simulation::VariantSource& source, const simulation::SequenceVariantOptions& options,
                     const fs::path& dir) {
  simulation::writeSequenceVariant(source, options, dir.string());
  return {io::TumSequence::open(dir.string()), io::loadCamera((dir / "camera.yaml").string())};
}

TEST(SequenceVariants, MillimetreDepthGivesTheSameMetricDepth) {
  const simulation::VariantSource source = smallSynthetic();
  const Written variant = writeAndOpen(source, kinds("mm-depth"), scratchDir("variant") / "mm");
  EXPECT_EQ(variant.camera.depth_factor, 1000.0);
  const cv::Mat raw = cv::imread(variant.sequence.frame(0).depth_path, cv::IMREAD_UNCHANGED);
  ASSERT_EQ(raw.type(), CV_16UC1);
  for (std::size_t i = 0; i < source.size; ++i) {
    const cv::Mat original = source.load(i).depth, read = variant.sequence.loadFrame(i, variant.camera).depth;
    std::size_t valid = 0;
    for (int v = 0; v < original.rows; v += 2)
      for (int u = 0; u < original.cols; u += 2) {
        const float z = original.at<float>(v, u);
        if (!(z > 0.0f)) continue;
        ++valid;
        ASSERT_NEAR(read.at<float>(v, u), z, 0.0005 + 1e-6) << "frame " << i << " pixel " << u << "," << v;
      }
    EXPECT_GT(valid, 300u);
  }
}

TEST(SequenceVariants, FocalVariantSeesEachPointWhereItsIntrinsicsSay) {
  const simulation::VariantSource source = smallSynthetic(2);
  simulation::SequenceVariantOptions options = kinds("focal");
  options.focal_length_px = 147.0;  // 1.13 times: as 585 px is to fr1's 517 px
  const Written variant = writeAndOpen(source, options, scratchDir("variant") / "focal");
  const double scale = 147.0 / source.camera.fx;
  EXPECT_DOUBLE_EQ(variant.camera.fx, 147.0);
  EXPECT_NEAR(variant.camera.fy, source.camera.fy * scale, 1e-9);
  EXPECT_EQ(variant.camera.cx, source.camera.cx);
  EXPECT_EQ(variant.camera.cy, source.camera.cy);
  EXPECT_EQ(variant.camera.width, source.camera.width);

  // A point seen by the original camera projects, through the variant's
  // intrinsics, to a pixel where the variant has (nearly) the same depth.
  const cv::Mat original = source.load(0).depth, zoomed = variant.sequence.loadFrame(0, variant.camera).depth;
  std::size_t checked = 0, agree = 0;
  for (int v = 0; v < original.rows; v += 2)
    for (int u = 0; u < original.cols; u += 2) {
      const float z = original.at<float>(v, u);
      if (!(z > 0.0f)) continue;
      const Eigen::Vector2d pixel = variant.camera.project(source.camera.backProject(u, v, z));
      const int pu = static_cast<int>(std::lround(pixel.x())), pv = static_cast<int>(std::lround(pixel.y()));
      if (pu < 0 || pv < 0 || pu >= zoomed.cols || pv >= zoomed.rows) continue;
      ++checked;
      agree += std::abs(zoomed.at<float>(pv, pu) - z) < 0.02f * z;
    }
  ASSERT_GT(checked, 300u);
  EXPECT_GT(static_cast<double>(agree) / checked, 0.95);
}

// Another sensor's resolution, same field of view: every point projects, through the variant's intrinsics, where
// the resized images show it (depth, and colour averaged over the pixels the new one covers).
TEST(SequenceVariants, ResolutionVariantSeesEachPointWhereItsIntrinsicsSay) {
  const simulation::VariantSource source = smallSynthetic(2);
  // 0.33: 160x120 becomes 53x40, each axis scaled by its own rounded ratio.
  for (const double scale : {0.5, 2.0, 0.33}) {
    simulation::SequenceVariantOptions options = kinds("resolution");
    options.resolution_scale = scale;
    const Written variant =
        writeAndOpen(source, options, scratchDir("variant") / ("resolution_" + std::to_string(scale)));
    EXPECT_EQ(variant.camera.width, std::lround(source.camera.width * scale));
    EXPECT_EQ(variant.camera.height, std::lround(source.camera.height * scale));
    const double sx = static_cast<double>(variant.camera.width) / source.camera.width;
    const double sy = static_cast<double>(variant.camera.height) / source.camera.height;
    EXPECT_NEAR(variant.camera.fx, source.camera.fx * sx, 1e-9);
    EXPECT_NEAR(variant.camera.fy, source.camera.fy * sy, 1e-9);
    EXPECT_NEAR(variant.camera.cx, (source.camera.cx + 0.5) * sx - 0.5, 1e-9);
    EXPECT_NEAR(variant.camera.cy, (source.camera.cy + 0.5) * sy - 0.5, 1e-9);
    const RgbdFrame original = source.load(0), resized = variant.sequence.loadFrame(0, variant.camera);
    ASSERT_EQ(resized.color.cols, variant.camera.width);
    ASSERT_EQ(resized.depth.rows, variant.camera.height);
    std::size_t checked = 0, depth_agrees = 0;
    double colour_error = 0.0;
    for (int v = 4; v < original.depth.rows - 4; v += 3)
      for (int u = 4; u < original.depth.cols - 4; u += 3) {
        const float z = original.depth.at<float>(v, u);
        if (!(z > 0.0f)) continue;
        const Eigen::Vector2d pixel = variant.camera.project(source.camera.backProject(u, v, z));
        const int pu = static_cast<int>(std::lround(pixel.x())), pv = static_cast<int>(std::lround(pixel.y()));
        ++checked;
        depth_agrees += std::abs(resized.depth.at<float>(pv, pu) - z) < 0.02f * z;
        // The blurred texture changes little over a pixel or two: the grey levels agree.
        colour_error +=
            std::abs(cv::norm(resized.color.at<cv::Vec3b>(pv, pu)) - cv::norm(original.color.at<cv::Vec3b>(v, u)));
      }
    ASSERT_GT(checked, 300u);
    EXPECT_GT(static_cast<double>(depth_agrees) / checked, 0.95) << "scale " << scale;
    EXPECT_LT(colour_error / checked, 12.0) << "scale " << scale;
  }
  simulation::SequenceVariantOptions too_small = kinds("resolution");
  too_small.resolution_scale = 0.05;
  EXPECT_THROW(simulation::writeSequenceVariant(source, too_small, (scratchDir("variant") / "tiny").string()),
               std::invalid_argument);
}

// Another aspect ratio (a 16:9 sensor beside a 4:3 one): the middle rows of colour and depth, each point where the
// cropped camera projects it; a crop after the depth has a camera of its own is refused.
TEST(SequenceVariants, CropVariantKeepsTheMiddleRowsWhereItsCameraSays) {
  simulation::VariantSource source = smallSynthetic(2);
  source.camera.distortion = {0.2, -0.4, 0.001, -0.002, 0.3};
  simulation::SequenceVariantOptions options = kinds("crop");
  options.crop_aspect = 16.0 / 9.0;
  const Written variant = writeAndOpen(source, options, scratchDir("variant_crop") / "crop");
  EXPECT_EQ(variant.camera.width, source.camera.width);
  EXPECT_EQ(variant.camera.height, std::lround(source.camera.width * 9.0 / 16.0));
  const int top = (source.camera.height - variant.camera.height) / 2;
  EXPECT_DOUBLE_EQ(variant.camera.cy, source.camera.cy - top);
  EXPECT_EQ(variant.camera.fx, source.camera.fx);
  EXPECT_EQ(variant.camera.distortion, source.camera.distortion);
  const RgbdFrame original = source.load(0), cropped = variant.sequence.loadFrame(0, variant.camera);
  ASSERT_EQ(cropped.color.rows, variant.camera.height);
  std::size_t checked = 0, agree = 0;
  for (int v = top; v < top + variant.camera.height; v += 3)
    for (int u = 0; u < original.depth.cols; u += 3) {
      const float z = original.depth.at<float>(v, u);
      if (!(z > 0.0f)) continue;
      const Eigen::Vector2d pixel = variant.camera.project(source.camera.backProject(u, v, z));
      const int pu = static_cast<int>(std::lround(pixel.x())), pv = static_cast<int>(std::lround(pixel.y()));
      ASSERT_TRUE(pu >= 0 && pv >= 0 && pu < cropped.depth.cols && pv < cropped.depth.rows);
      ++checked;
      agree += std::abs(cropped.depth.at<float>(pv, pu) - z) < 0.02f * z &&
               cropped.color.at<cv::Vec3b>(pv, pu) == original.color.at<cv::Vec3b>(v, u);
    }
  ASSERT_GT(checked, 300u);
  EXPECT_GT(static_cast<double>(agree) / checked, 0.99);
  simulation::SequenceVariantOptions late = kinds("unregistered,crop");
  EXPECT_THROW(
      simulation::writeSequenceVariant(smallSynthetic(2), late, (scratchDir("variant_crop") / "late").string()),
      std::invalid_argument);
  simulation::SequenceVariantOptions taller = kinds("crop");
  taller.crop_aspect = 1.0;  // taller than the source: not a crop
  EXPECT_THROW(
      simulation::writeSequenceVariant(smallSynthetic(2), taller, (scratchDir("variant_crop") / "tall").string()),
      std::invalid_argument);
}

// A depth camera of another resolution than the colour camera's, registered or not, with lens distortion or not:
// every depth pixel shows, through the depth camera's intrinsics and pose, the depth the source shows at the
// (distorted) colour pixel its point projects to. The colour images are left as they are.
TEST(SequenceVariants, DepthResolutionVariantSeesEachPointWhereTheDepthCameraSays) {
  const fs::path dir = scratchDir("variant_depth_resolution");
  simulation::VariantSource distorted = smallSynthetic(2);
  distorted.camera.distortion = {0.2, -0.4, 0.001, -0.002, 0.3};
  int case_index = 0;
  for (const auto& [source, names, scale] :
       {std::tuple{smallSynthetic(2), "depth-resolution", 0.5}, std::tuple{distorted, "depth-resolution", 0.5},
        std::tuple{smallSynthetic(2), "unregistered,depth-resolution", 0.37},
        std::tuple{distorted, "unregistered,depth-resolution", 2.0}}) {
    const std::string what =
        std::string(names) + " " + std::to_string(scale) + (source.camera.hasDistortion() ? " distorted" : "");
    simulation::SequenceVariantOptions options = kinds(names);
    options.depth_resolution_scale = scale;
    const Written variant = writeAndOpen(source, options, dir / std::to_string(case_index++));
    ASSERT_TRUE(variant.camera.unregistered_depth.has_value()) << what;
    const DepthCamera& sensor = *variant.camera.unregistered_depth;
    EXPECT_EQ(variant.camera.depthImageSize(),
              cv::Size(std::lround(source.camera.width * scale), std::lround(source.camera.height * scale)))
        << what;
    const RgbdFrame original = source.load(0), read = variant.sequence.loadFrame(0, variant.camera);
    EXPECT_EQ(cv::norm(read.color, original.color, cv::NORM_INF), 0.0) << what;
    ASSERT_EQ(read.depth.size(), variant.camera.depthImageSize()) << what;
    PinholeCamera depth_camera;
    depth_camera.fx = sensor.fx;
    depth_camera.fy = sensor.fy;
    depth_camera.cx = sensor.cx;
    depth_camera.cy = sensor.cy;
    const Eigen::Isometry3d depth_in_color = sensor.depthInColor();
    std::size_t checked = 0, agree = 0;
    for (int v = 2; v < read.depth.rows - 2; ++v)
      for (int u = 2; u < read.depth.cols - 2; ++u) {
        const float z = read.depth.at<float>(v, u);
        if (!(z > 0.0f)) continue;
        const Eigen::Vector3d point = depth_in_color * depth_camera.backProject(u, v, z);
        std::vector<cv::Point2f> pixel;
        cv::projectPoints(
            std::vector<cv::Point3f>{cv::Point3f(static_cast<float>(point.x()), static_cast<float>(point.y()),
                                                 static_cast<float>(point.z()))},
            cv::Vec3d(), cv::Vec3d(), source.camera.cameraMatrix(), source.camera.distortionCoefficients(), pixel);
        const int pu = static_cast<int>(std::lround(pixel[0].x)), pv = static_cast<int>(std::lround(pixel[0].y));
        if (pu < 1 || pv < 1 || pu >= original.depth.cols - 1 || pv >= original.depth.rows - 1) continue;
        ++checked;
        // The box's edges move by a pixel in the resampling: the depth there is one of the two sides'.
        agree += std::abs(original.depth.at<float>(pv, pu) - point.z()) < 0.02 * point.z();
      }
    ASSERT_GT(checked, 300u) << what;
    EXPECT_GT(static_cast<double>(agree) / checked, 0.95) << what;
  }
  // After the kinds that assume the depth image is the colour image's size only.
  simulation::SequenceVariantOptions wrong_order = kinds("depth-resolution,focal");
  EXPECT_THROW(simulation::writeSequenceVariant(smallSynthetic(2), wrong_order, (dir / "wrong_order").string()),
               std::invalid_argument);
  EXPECT_FALSE(fs::exists(dir / "wrong_order"));
  EXPECT_THROW(simulation::zoomedCamera(simulation::depthResizedCamera(smallSynthetic(2).camera, 0.5), 1.2),
               std::invalid_argument);
}

// A noisier depth sensor: errors of coefficient z^2 around the true depth, in patches when correlated, holes kept.
TEST(SequenceVariants, NoisyDepthGrowsWithTheSquareOfTheDistanceAndComesInPatches) {
  cv::Mat depth(240, 320, CV_32F, cv::Scalar(2.0f));
  depth(cv::Rect(0, 0, 160, 240)).setTo(1.0f);
  depth.at<float>(100, 200) = 0.0f;  // no reading
  const auto measure = [&](double correlation_px) {
    cv::RNG rng(3);
    const cv::Mat noisy = simulation::noisyDepth(depth, 0.01, correlation_px, rng);
    EXPECT_EQ(noisy.at<float>(100, 200), 0.0f);
    cv::Mat error = noisy - depth;
    cv::Scalar near_mean, near_sigma, far_mean, far_sigma;
    cv::meanStdDev(error(cv::Rect(10, 10, 140, 220)), near_mean, near_sigma);
    cv::meanStdDev(error(cv::Rect(170, 10, 140, 80)), far_mean, far_sigma);
    EXPECT_NEAR(near_sigma[0], 0.01, 0.002);  // 0.01 * 1^2
    EXPECT_NEAR(far_sigma[0], 0.04, 0.008);   // 0.01 * 2^2
    EXPECT_NEAR(far_mean[0], 0.0, 0.01);
    // Correlation of horizontal neighbours' errors on the far half.
    double products = 0.0, squares = 0.0;
    for (int v = 10; v < 90; ++v)
      for (int u = 170; u < 309; ++u) {
        products += error.at<float>(v, u) * error.at<float>(v, u + 1);
        squares += error.at<float>(v, u) * error.at<float>(v, u);
      }
    return products / squares;
  };
  EXPECT_LT(std::abs(measure(0.0)), 0.1);
  EXPECT_GT(measure(2.0), 0.8);
  cv::RNG rng(1);
  EXPECT_THROW(simulation::noisyDepth(depth, -0.01, 2.0, rng), std::invalid_argument);
  EXPECT_THROW(simulation::noisyDepth(cv::Mat(4, 4, CV_8U), 0.01, 2.0, rng), std::invalid_argument);
}

TEST(SequenceVariants, UnregisteredDepthIsSeenFromTheOffsetCamera) {
  // A near square (1 m) in front of a wall (2 m): seen from 2.5 cm to the
  // right, the square moves fx * 0.025 / 1 px to the left, the wall half that.
  PinholeCamera camera = tumCamera(1);
  camera.distortion = {};
  cv::Mat depth(camera.height, camera.width, CV_32F, cv::Scalar(2.0f));
  depth(cv::Rect(300, 200, 100, 100)).setTo(1.0f);
  Eigen::Isometry3d depth_in_color = Eigen::Isometry3d::Identity();
  depth_in_color.translation() = Eigen::Vector3d(0.025, 0.0, 0.0);
  const cv::Mat moved = simulation::unregisteredDepth(depth, camera, depth_in_color);
  int left_edge = -1;
  for (int u = 200; u < 400 && left_edge < 0; ++u)
    if (moved.at<float>(250, u) < 1.5f) left_edge = u;
  EXPECT_NEAR(left_edge, 300 - camera.fx * 0.025, 1.0);
  EXPECT_NEAR(moved.at<float>(250, 500), 2.0f, 1e-4);
  EXPECT_THROW(simulation::unregisteredDepth(depth(cv::Rect(0, 0, 320, 240)).clone(), camera, depth_in_color),
               std::invalid_argument);
}

TEST(SequenceVariants, AnUnregisteredVariantsCameraFileNamesItsDepthCameraUnlessAskedNot) {
  const simulation::VariantSource source = smallSynthetic(2);
  simulation::SequenceVariantOptions options = kinds("unregistered,focal");
  const Written variant = writeAndOpen(source, options, scratchDir("variant") / "calibrated");
  ASSERT_TRUE(variant.camera.unregistered_depth.has_value());
  const DepthCamera& depth = *variant.camera.unregistered_depth;
  EXPECT_NEAR(depth.translation_m[0], 0.025, 1e-12);
  EXPECT_NEAR(depth.rotation_rad[1], 0.5 * M_PI / 180.0, 1e-12);
  // Zoomed after the depth was moved: the depth camera's intrinsics zoomed with the colour camera's.
  EXPECT_NEAR(depth.fx, variant.camera.fx, 1e-9);
  EXPECT_NEAR(depth.cx, variant.camera.cx, 1e-9);
  options.describe_depth_camera = false;
  EXPECT_FALSE(writeAndOpen(source, options, scratchDir("variant") / "bare").camera.unregistered_depth.has_value());
}

TEST(SequenceVariants, JpegColourIsWrittenAsJpegAndStaysCloseToTheOriginal) {
  const simulation::VariantSource source = smallSynthetic(2);
  const Written variant = writeAndOpen(source, kinds("jpeg"), scratchDir("variant") / "jpeg");
  EXPECT_EQ(fs::path(variant.sequence.frame(0).rgb_path).extension(), ".jpg");
  const cv::Mat original = source.load(1).color, read = variant.sequence.loadFrame(1, variant.camera).color;
  EXPECT_GT(cv::PSNR(original, read), 28.0);
  EXPECT_GT(cv::norm(original, read, cv::NORM_INF), 0.0) << "JPEG at quality 75 is lossy";
}

TEST(SequenceVariants, BurstsDegradeTheListedFramesOnlyAndKeepTimestampsAndGroundTruth) {
  const simulation::VariantSource source = smallSynthetic(6);
  simulation::SequenceVariantOptions options = kinds("burst");
  options.burst_start = 1;
  options.burst_period = 3;
  options.burst_length = 1;
  const fs::path dir = scratchDir("variant") / "burst";
  const Written variant = writeAndOpen(source, options, dir);
  const auto degraded = simulation::readDegradedFrames((dir / "bursts.txt").string());
  ASSERT_EQ(degraded.size(), 2u);
  EXPECT_EQ(degraded[0].index, 1u);
  EXPECT_EQ(degraded[0].how, "blur");
  EXPECT_EQ(degraded[1].index, 4u);
  EXPECT_EQ(degraded[1].how, "noise");
  ASSERT_EQ(variant.sequence.size(), source.size);
  ASSERT_TRUE(variant.sequence.hasGroundTruth());
  for (std::size_t i = 0; i < source.size; ++i) {
    const RgbdFrame original = source.load(i), read = variant.sequence.loadFrame(i, variant.camera);
    EXPECT_NEAR(read.timestamp, original.timestamp, 1e-6);
    const bool is_degraded = i == 1 || i == 4;
    EXPECT_EQ(cv::norm(original.color, read.color, cv::NORM_INF) > 0.0, is_degraded) << "frame " << i;
    const auto truth = variant.sequence.groundTruthAt(read.timestamp);
    ASSERT_TRUE(truth) << "frame " << i;
    EXPECT_TRUE(truth->isApprox(source.groundtruth[i].pose, 1e-6)) << "frame " << i;
  }
}

TEST(SequenceVariants, ThereAndBackShowsEvenFramesForwardThenOddFramesBackWithTheirGroundTruth) {
  simulation::VariantSource source = smallSynthetic(7);
  source.groundtruth.erase(source.groundtruth.begin() + 5);  // frame 5's pose: interpolated from 4 and 6
  const fs::path dir = scratchDir("variant") / "there_and_back";
  const Written variant = writeAndOpen(source, kinds("there-and-back"), dir);
  const std::vector<std::size_t> shown = {0, 2, 4, 6, 5, 3, 1};
  ASSERT_EQ(variant.sequence.size(), shown.size());
  double previous = -1.0;
  for (std::size_t j = 0; j < shown.size(); ++j) {
    const RgbdFrame original = source.load(shown[j]), read = variant.sequence.loadFrame(j, variant.camera);
    EXPECT_EQ(cv::norm(original.color, read.color, cv::NORM_INF), 0.0) << "frame " << j;
    EXPECT_GT(read.timestamp, previous) << "frame " << j << ": time must go on";
    if (j < 4) {
      EXPECT_NEAR(read.timestamp, original.timestamp, 1e-6) << "forward frames keep their time";
    }
    // The way back is timed at the forward part's interval, 0.1 s (every other frame).
    if (j >= 4) {
      EXPECT_NEAR(read.timestamp - previous, 0.1, 1e-6) << "frame " << j;
    }
    EXPECT_NEAR(variant.sequence.frame(j).depth_timestamp - read.timestamp, 0.01, 1e-6) << "frame " << j;
    previous = read.timestamp;
    const auto truth = variant.sequence.groundTruthAt(read.timestamp);
    ASSERT_TRUE(truth) << "frame " << j;
    EXPECT_NEAR(truth->translation().x(), 0.01 * static_cast<double>(shown[j]), 1e-6) << "frame " << j;
  }
  EXPECT_THROW(simulation::thereAndBack(smallSynthetic(3)), std::invalid_argument);
}

TEST(SequenceVariants, FrameStepKeepsEveryNthFrameWithItsTimesAndTheWholeGroundTruth) {
  const simulation::VariantSource source = smallSynthetic(7);
  simulation::SequenceVariantOptions options = kinds("frame-step");
  options.frame_step = 3;
  const Written variant = writeAndOpen(source, options, scratchDir("variant") / "frame_step");
  const std::vector<std::size_t> kept = {0, 3, 6};
  ASSERT_EQ(variant.sequence.size(), kept.size());
  for (std::size_t j = 0; j < kept.size(); ++j) {
    const RgbdFrame original = source.load(kept[j]), read = variant.sequence.loadFrame(j, variant.camera);
    EXPECT_EQ(cv::norm(original.color, read.color, cv::NORM_INF), 0.0) << "frame " << j;
    EXPECT_NEAR(read.timestamp, original.timestamp, 1e-6) << "frame " << j;
    EXPECT_NEAR(variant.sequence.frame(j).depth_timestamp, source.depth_timestamp(kept[j]), 1e-6) << "frame " << j;
  }
  EXPECT_EQ(variant.sequence.groundTruth().size(), source.groundtruth.size()) << "every pose, for the association";
  EXPECT_EQ(simulation::everyNthFrame(source, 1).size, source.size);
  EXPECT_EQ(simulation::everyNthFrame(source, 10).size, 1u);
  EXPECT_THROW(simulation::everyNthFrame(source, 0), std::invalid_argument);
  options.frame_step = 31;
  EXPECT_THROW(simulation::writeSequenceVariant(source, options, (scratchDir("variant") / "step31").string()),
               std::invalid_argument);
}

TEST(SequenceVariants, FrameStepComesBeforeThereAndBack) {
  const simulation::VariantSource source = smallSynthetic(8);
  const Written variant = writeAndOpen(source, kinds("there-and-back,frame-step"), scratchDir("variant") / "tb_step");
  // Frames 0, 2, 4, 6 kept, then there and back over them: 0, 4 forward and 6, 2 back.
  const std::vector<std::size_t> shown = {0, 4, 6, 2};
  ASSERT_EQ(variant.sequence.size(), shown.size());
  for (std::size_t j = 0; j < shown.size(); ++j)
    EXPECT_EQ(cv::norm(source.load(shown[j]).color, variant.sequence.loadFrame(j, variant.camera).color, cv::NORM_INF),
              0.0)
        << "frame " << j;
}

TEST(SequenceVariants, ExposureChangesEachFramesLightSmoothlyWithinItsStops) {
  simulation::SequenceVariantOptions options = kinds("exposure");
  options.exposure_stops = 1.0;
  options.exposure_period_frames = 30.0;
  double lowest = 0.0, highest = 0.0, largest_step = 0.0, previous = simulation::exposureStops(0, options);
  for (std::size_t i = 0; i < 300; ++i) {
    const double stops = simulation::exposureStops(i, options);
    EXPECT_LE(std::abs(stops), 1.0 + 1e-12) << "frame " << i;
    EXPECT_EQ(stops, simulation::exposureStops(i, options)) << "frame " << i << ": frame i's own";
    lowest = std::min(lowest, stops);
    highest = std::max(highest, stops);
    largest_step = std::max(largest_step, std::abs(stops - previous));
    previous = stops;
  }
  EXPECT_LT(lowest, -0.5);
  EXPECT_GT(highest, 0.5);
  // Auto exposure follows the scene, without jumps: at most the sinusoids' steepest slope a frame.
  EXPECT_LE(largest_step, 2.0 * M_PI / 30.0 * (0.6 + 0.4 / 0.37));
  EXPECT_GT(largest_step, 0.1);
  simulation::SequenceVariantOptions other = options;
  other.seed = 2;
  EXPECT_NE(simulation::exposureStops(5, options), simulation::exposureStops(5, other));

  // Written: a brighter frame is brighter, a darker one darker, depth untouched.
  const simulation::VariantSource source = smallSynthetic(12);
  const Written variant = writeAndOpen(source, options, scratchDir("variant") / "exposure");
  for (std::size_t i = 0; i < source.size; ++i) {
    const RgbdFrame original = source.load(i), read = variant.sequence.loadFrame(i, variant.camera);
    const double stops = simulation::exposureStops(i, options);
    const double before = cv::mean(original.color)[0], after = cv::mean(read.color)[0];
    if (stops > 0.1) EXPECT_GT(after, before) << "frame " << i;
    if (stops < -0.1) EXPECT_LT(after, before) << "frame " << i;
    EXPECT_EQ(cv::norm(original.depth, read.depth, cv::NORM_INF), 0.0) << "frame " << i;
  }
}

TEST(ImageDegradations, ExposureIsLinearLightGainSaturating) {
  cv::Mat grey(4, 4, CV_8UC1);
  for (int i = 0; i < 16; ++i) grey.at<unsigned char>(i / 4, i % 4) = static_cast<unsigned char>(16 * i + 10);
  EXPECT_EQ(cv::norm(simulation::changeExposure(grey, 0.0), grey, cv::NORM_INF), 0.0);
  const cv::Mat mid(1, 1, CV_8UC1, cv::Scalar(100));
  // Twice the light: 100 becomes 100 * 2^(1 / 2.2) (8-bit values are gamma 2.2), half: 100 / 2^(1 / 2.2).
  EXPECT_NEAR(simulation::changeExposure(mid, 1.0).at<unsigned char>(0, 0), 100.0 * std::pow(2.0, 1.0 / 2.2), 0.6);
  EXPECT_NEAR(simulation::changeExposure(mid, -1.0).at<unsigned char>(0, 0), 100.0 / std::pow(2.0, 1.0 / 2.2), 0.6);
  const cv::Mat bright(1, 1, CV_8UC3, cv::Scalar(250, 200, 20));
  const cv::Vec3b up = simulation::changeExposure(bright, 2.0).at<cv::Vec3b>(0, 0);
  EXPECT_EQ(up[0], 255);  // the highlights clip
  EXPECT_EQ(up[1], 255);
  EXPECT_GT(up[2], 20);
  EXPECT_THROW(simulation::changeExposure(cv::Mat(2, 2, CV_32F), 1.0), std::invalid_argument);
  EXPECT_THROW(simulation::changeExposure(grey, 9.0), std::invalid_argument);
}

TEST(SequenceVariants, TheSameSeedWritesTheSameImages) {
  const simulation::VariantSource source = smallSynthetic(2);
  const fs::path a = scratchDir("variant") / "a", b = scratchDir("variant") / "b";
  const Written first = writeAndOpen(source, kinds("blur,low-light"), a);
  const Written second = writeAndOpen(source, kinds("blur,low-light"), b);
  for (std::size_t i = 0; i < source.size; ++i)
    EXPECT_EQ(cv::norm(first.sequence.loadFrame(i, first.camera).color,
                       second.sequence.loadFrame(i, second.camera).color, cv::NORM_INF),
              0.0);
}

TEST(SequenceVariants, BadOptionsAndOutputsFailBeforeWritingAnything) {
  const simulation::VariantSource source = smallSynthetic(1);
  const fs::path dir = scratchDir("variant") / "out";
  simulation::SequenceVariantOptions options = kinds("jpeg");
  options.jpeg_quality = 0;
  EXPECT_THROW(simulation::writeSequenceVariant(source, options, dir.string()), std::invalid_argument);
  EXPECT_FALSE(fs::exists(dir));
  options = kinds("burst");
  options.burst_period = 1;
  options.burst_length = 2;
  EXPECT_THROW(simulation::writeSequenceVariant(source, options, dir.string()), std::invalid_argument);
  EXPECT_THROW(simulation::writeSequenceVariant(source, simulation::SequenceVariantOptions{}, dir.string()),
               std::invalid_argument);
  EXPECT_FALSE(fs::exists(dir));

  fs::create_directories(dir);
  std::ofstream(dir / "keep.txt") << "mine\n";
  EXPECT_THROW(simulation::writeSequenceVariant(source, kinds("jpeg"), dir.string()), std::runtime_error);
  EXPECT_TRUE(fs::exists(dir / "keep.txt"));
  EXPECT_FALSE(fs::exists(dir / "rgb.txt"));

  EXPECT_THROW(simulation::parseVariantKinds("jpeg,sepia"), std::invalid_argument);
  EXPECT_THROW(simulation::parseVariantKinds("jpeg,jpeg"), std::invalid_argument);
  const fs::path bursts = dir / "bursts.txt";
  std::ofstream(bursts) << "# header\n3 1.5 blur\n4 x noise\n";
  try {
    simulation::readDegradedFrames(bursts.string());
    FAIL() << "a malformed line was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("bursts.txt:3"), std::string::npos) << e.what();
  }
}

TEST(ImageDegradations, RefuseWhatTheyCannotDegrade) {
  cv::RNG rng(1);
  const cv::Mat color(48, 64, CV_8UC3, cv::Scalar::all(100));
  EXPECT_THROW(simulation::motionBlur(cv::Mat(), 5.0, 0.0), std::invalid_argument);
  EXPECT_THROW(simulation::motionBlur(color, 0.5, 0.0), std::invalid_argument);
  EXPECT_THROW(simulation::addGaussianNoise(cv::Mat(4, 4, CV_32F), 1.0, rng), std::invalid_argument);
  EXPECT_THROW(simulation::lowLight(color, 0.0, 1.0, 1.0, rng), std::invalid_argument);
  EXPECT_THROW(simulation::zoomImage(color, tumCamera(1), 1.1, 1), std::invalid_argument);  // 64x48 vs 640x480
  EXPECT_LT(cv::mean(simulation::lowLight(color, 0.3, 1.0, 0.0, rng))[0], 31.0);
}

}  // namespace
