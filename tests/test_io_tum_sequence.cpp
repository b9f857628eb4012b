#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "test_support.h"
#include "weighted_icp/io/tum_sequence.h"

using namespace weighted_icp;
namespace fs = std::filesystem;
using weighted_icp::testing::writeFile;

namespace {

/// timestamp -> file name of a TUM list, parsed here independently of the library.
std::map<double, std::string> readList(const fs::path& path) {
  std::map<double, std::string> entries;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    double timestamp;
    std::string name;
    fields >> timestamp >> name;
    entries[timestamp] = name;
  }
  return entries;
}

std::string errorOf(const std::function<void()>& action) {
  try {
    action();
  } catch (const std::exception& e) {
    return e.what();
  }
  return {};
}

/// A small camera for the synthetic sequences.
PinholeCamera smallCamera() {
  PinholeCamera camera = tumCamera(3);
  camera.width = 64;
  camera.height = 48;
  return camera;
}

/// A sequence of `frames` uniform 64x48 frames, colour (B, G, R) = (30, 60, 90)
/// and raw depth `raw_depth`, colour and depth 5 ms apart.
fs::path writeSequence(const std::string& name, int frames, std::uint16_t raw_depth = 7500) {
  const fs::path dir = weighted_icp::testing::scratchDir(name);
  fs::create_directories(dir / "rgb");
  fs::create_directories(dir / "depth");
  std::ofstream rgb_list(dir / "rgb.txt"), depth_list(dir / "depth.txt");
  rgb_list << "# color images\n# file: 'synthetic'\n# timestamp filename\n";
  depth_list << "# depth maps\n# file: 'synthetic'\n# timestamp filename\n";
  for (int k = 0; k < frames; ++k) {
    const std::string rgb_stamp = std::to_string(100 + k) + ".000000";
    const std::string depth_stamp = std::to_string(100 + k) + ".005000";
    cv::imwrite((dir / "rgb" / (rgb_stamp + ".png")).string(), cv::Mat(48, 64, CV_8UC3, cv::Scalar(30, 60, 90)));
    cv::imwrite((dir / "depth" / (depth_stamp + ".png")).string(), cv::Mat(48, 64, CV_16UC1, cv::Scalar(raw_depth)));
    rgb_list << rgb_stamp << " rgb/" << rgb_stamp << ".png\n";
    depth_list << depth_stamp << " depth/" << depth_stamp << ".png\n";
  }
  return dir;
}

const char* const kRealSequences[] = {"tum_fr1_xyz_head", "tum_fr3_teddy_head"};

}  // namespace

TEST(TumSequence, RealSequencesAssociateAsTheBenchmarkRuleDemands) {
  for (const char* name : kRealSequences) {
    SCOPED_TRACE(name);
    const fs::path dir = weighted_icp::testing::dataDir() / name;
    WEIGHTED_ICP_REQUIRE_FILE(dir / "rgb.txt");
    const auto rgb = readList(dir / "rgb.txt");
    const auto depth = readList(dir / "depth.txt");
    const io::TumSequence sequence = io::TumSequence::open(dir.string());
    ASSERT_GT(sequence.size(), 0u);
    ASSERT_LE(sequence.size(), std::min(rgb.size(), depth.size()));

    std::set<double> used_rgb, used_depth;
    for (std::size_t i = 0; i < sequence.size(); ++i) {
      const io::TumFrame& frame = sequence.frame(i);
      EXPECT_LT(std::abs(frame.rgb_timestamp - frame.depth_timestamp), 0.02);
      if (i > 0) {
        EXPECT_LT(sequence.frame(i - 1).rgb_timestamp, frame.rgb_timestamp);  // sorted, each once
      }
      EXPECT_TRUE(used_depth.insert(frame.depth_timestamp).second) << "depth used twice";
      used_rgb.insert(frame.rgb_timestamp);
      ASSERT_EQ(rgb.count(frame.rgb_timestamp), 1u);
      ASSERT_EQ(depth.count(frame.depth_timestamp), 1u);
      EXPECT_EQ(fs::path(frame.rgb_path), dir / rgb.at(frame.rgb_timestamp));
      EXPECT_EQ(fs::path(frame.depth_path), dir / depth.at(frame.depth_timestamp));
    }
    // Greedy association leaves no pair of unused timestamps within the limit.
    for (const auto& [rgb_time, rgb_file] : rgb) {
      if (used_rgb.count(rgb_time)) continue;
      for (const auto& [depth_time, depth_file] : depth)
        EXPECT_FALSE(!used_depth.count(depth_time) && std::abs(rgb_time - depth_time) < 0.02)
            << rgb_file << " and " << depth_file << " were left unpaired";
    }
    EXPECT_THROW(sequence.frame(sequence.size()), std::out_of_range);
  }
}

TEST(TumSequence, RealImagesLoadWithMetricDepth) {
  const fs::path dir = weighted_icp::testing::dataDir() / "tum_fr1_xyz_head";
  WEIGHTED_ICP_REQUIRE_FILE(dir / "rgb.txt");
  const io::TumSequence sequence = io::TumSequence::open(dir.string());
  const PinholeCamera camera = tumCamera(1);
  for (const std::size_t i : {std::size_t{0}, sequence.size() / 2, sequence.size() - 1}) {
    SCOPED_TRACE(sequence.frame(i).rgb_path);
    const RgbdFrame images = sequence.loadFrame(i, camera);
    EXPECT_EQ(images.color.type(), CV_8UC3);
    EXPECT_EQ(images.gray().type(), CV_8UC1);
    EXPECT_EQ(images.depth.type(), CV_32FC1);
    for (const cv::Mat& image : {images.color, images.gray(), images.depth}) {
      EXPECT_EQ(image.cols, 640);
      EXPECT_EQ(image.rows, 480);
    }
    // The stored values divided by the depth factor, 0 kept where there is no reading.
    const cv::Mat raw = cv::imread(sequence.frame(i).depth_path, cv::IMREAD_UNCHANGED);
    cv::Mat expected;
    raw.convertTo(expected, CV_32F, 1.0 / 5000.0);
    EXPECT_LT(cv::norm(images.depth, expected, cv::NORM_INF), 1e-6);
    EXPECT_EQ(images.validDepthPixels(), static_cast<std::size_t>(cv::countNonZero(raw)));
    EXPECT_GT(images.validDepthPixels(), 640u * 480u / 2);

    std::vector<float> valid;
    for (auto it = images.depth.begin<float>(); it != images.depth.end<float>(); ++it)
      if (*it > 0.0f) valid.push_back(*it);
    std::nth_element(valid.begin(), valid.begin() + valid.size() / 2, valid.end());
    const float median = valid[valid.size() / 2];
    EXPECT_GT(median, 0.5f);
    EXPECT_LT(median, 3.0f);
  }
}

TEST(TumSequence, GroundTruthIsFoundForEveryFrame) {
  const fs::path dir = weighted_icp::testing::dataDir() / "tum_fr1_xyz_head";
  WEIGHTED_ICP_REQUIRE_FILE(dir / "groundtruth.txt");
  const io::TumSequence sequence = io::TumSequence::open(dir.string());
  ASSERT_TRUE(sequence.hasGroundTruth());
  const Trajectory groundtruth = io::readTrajectory((dir / "groundtruth.txt").string());
  for (std::size_t i = 0; i < sequence.size(); ++i) {
    const double t = sequence.frame(i).rgb_timestamp;
    const auto pose = sequence.groundTruthAt(t);
    ASSERT_TRUE(pose.has_value()) << "no ground truth at " << t;
    // The nearest pose, found by scanning them all.
    const auto nearest = std::min_element(groundtruth.begin(), groundtruth.end(), [&](const auto& a, const auto& b) {
      return std::abs(a.timestamp - t) < std::abs(b.timestamp - t);
    });
    EXPECT_TRUE(pose->isApprox(nearest->pose)) << "at " << t;
  }
  EXPECT_FALSE(sequence.groundTruthAt(sequence.frame(0).rgb_timestamp - 100.0).has_value());
}

TEST(TumSequence, SyntheticFramesLoadExactly) {
  const fs::path dir = writeSequence("tum_synthetic", 3, 7500);
  const io::TumSequence sequence = io::TumSequence::open(dir.string());
  ASSERT_EQ(sequence.size(), 3u);
  EXPECT_EQ(sequence.frame(1).rgb_timestamp, 101.0);
  EXPECT_EQ(sequence.frame(1).depth_timestamp, 101.005);
  EXPECT_FALSE(sequence.hasGroundTruth());
  EXPECT_THROW(sequence.groundTruthAt(101.0), std::runtime_error);

  PinholeCamera camera = smallCamera();
  RgbdFrame images = sequence.loadFrame(1, camera);
  EXPECT_EQ(images.validDepthPixels(), 64u * 48u);
  EXPECT_LT(cv::norm(images.depth - 1.5, cv::NORM_INF), 1e-6);  // 7500 / 5000
  EXPECT_EQ(images.color.at<cv::Vec3b>(10, 10), cv::Vec3b(30, 60, 90));
  // ITU-R BT.601 luma of (R, G, B) = (90, 60, 30) is 65.55.
  EXPECT_NEAR(images.gray().at<std::uint8_t>(10, 10), 65.55, 1.0);

  camera.depth_factor = 1000.0;
  images = sequence.loadFrame(1, camera);
  EXPECT_LT(cv::norm(images.depth - 7.5, cv::NORM_INF), 1e-5);

  camera.depth_factor = 0.0;
  EXPECT_THROW(sequence.loadFrame(1, camera), std::invalid_argument);
}

TEST(TumSequence, EmptyDepthIsReportedNotThrown) {
  const fs::path dir = writeSequence("tum_empty_depth", 2, 0);
  const RgbdFrame images = io::TumSequence::open(dir.string()).loadFrame(0, smallCamera());
  EXPECT_EQ(images.validDepthPixels(), 0u);
  EXPECT_EQ(cv::countNonZero(images.depth), 0);
}

TEST(TumSequence, MissingFolderAndListsAreNamed) {
  const fs::path absent = weighted_icp::testing::scratchDir("tum_absent") / "nothing_here";
  EXPECT_NE(errorOf([&] { io::TumSequence::open(absent.string()); }).find(absent.string()), std::string::npos);

  const fs::path dir = writeSequence("tum_no_depth_list", 2);
  fs::remove(dir / "depth.txt");
  const std::string error = errorOf([&] { io::TumSequence::open(dir.string()); });
  EXPECT_NE(error.find((dir / "depth.txt").string()), std::string::npos) << error;
}

TEST(TumSequence, ListLineNamingNoFileIsNamedWithItsLine) {
  const fs::path dir = writeSequence("tum_line_without_file", 2);
  writeFile(dir / "rgb.txt", "# color images\n100.000000 rgb/100.000000.png\n\n101.000000\n");
  const std::string error = errorOf([&] { io::TumSequence::open(dir.string()); });
  EXPECT_NE(error.find((dir / "rgb.txt").string() + ":4:"), std::string::npos) << error;
}

TEST(TumSequence, MissingImageFileIsNamedWithItsLine) {
  const fs::path dir = writeSequence("tum_missing_image", 3);
  fs::remove(dir / "depth" / "101.005000.png");
  const std::string error = errorOf([&] { io::TumSequence::open(dir.string()); });
  EXPECT_NE(error.find((dir / "depth.txt").string() + ":5:"), std::string::npos) << error;
  EXPECT_NE(error.find("101.005000.png"), std::string::npos) << error;
}

// A name the file system refuses (longer than it allows) is named with its list's line, not left to
// std::filesystem's error, which names neither (a fuzzed list).
TEST(TumSequence, AnImageNameTheFileSystemRefusesIsNamedWithItsLine) {
  const fs::path dir = writeSequence("tum_name_too_long", 2);
  writeFile(dir / "rgb.txt", "# color images\n100.000000 rgb/" + std::string(5000, 'x') + ".png\n");
  const std::string error = errorOf([&] { io::TumSequence::open(dir.string()); });
  EXPECT_NE(error.find((dir / "rgb.txt").string() + ":2:"), std::string::npos) << error;
  EXPECT_NE(error.find("cannot use the image file name"), std::string::npos) << error;
  EXPECT_LT(error.size(), 1000u) << "the name is clipped";
}

TEST(TumSequence, ImageProblemsAreNamedWhenLoading) {
  const fs::path dir = writeSequence("tum_bad_images", 4);
  // Frame 0: depth of another size. Frame 1: colour that is not an image.
  // Frame 2: 8-bit depth. Frame 3: images fine, but not the camera's size.
  cv::imwrite((dir / "depth" / "100.005000.png").string(), cv::Mat(24, 32, CV_16UC1, cv::Scalar(5000)));
  writeFile(dir / "rgb" / "101.000000.png", "not a png");
  cv::imwrite((dir / "depth" / "102.005000.png").string(), cv::Mat(48, 64, CV_8UC1, cv::Scalar(50)));
  const io::TumSequence sequence = io::TumSequence::open(dir.string());
  const PinholeCamera camera = smallCamera();

  std::string error = errorOf([&] { sequence.loadFrame(0, camera); });
  EXPECT_NE(error.find(sequence.frame(0).depth_path), std::string::npos) << error;
  EXPECT_NE(error.find("32x24"), std::string::npos) << error;
  EXPECT_NE(error.find("64x48"), std::string::npos) << error;

  error = errorOf([&] { sequence.loadFrame(1, camera); });
  EXPECT_NE(error.find(sequence.frame(1).rgb_path), std::string::npos) << error;

  error = errorOf([&] { sequence.loadFrame(2, camera); });
  EXPECT_NE(error.find(sequence.frame(2).depth_path), std::string::npos) << error;
  EXPECT_NE(error.find("16-bit"), std::string::npos) << error;

  error = errorOf([&] { sequence.loadFrame(3, tumCamera(3)); });
  EXPECT_NE(error.find(sequence.frame(3).rgb_path), std::string::npos) << error;
  EXPECT_NE(error.find("640x480"), std::string::npos) << error;

  // An image removed after opening is still reported, not a crash.
  fs::remove(sequence.frame(3).rgb_path);
  error = errorOf([&] { sequence.loadFrame(3, camera); });
  EXPECT_NE(error.find(sequence.frame(3).rgb_path), std::string::npos) << error;
}

// A depth camera of its own resolution: depth images of its size load (in metres, not resized), others are named
// with the size the camera file gives.
TEST(TumSequence, DepthImagesOfTheDepthCamerasOwnSizeLoad) {
  const fs::path dir = writeSequence("tum_depth_camera_size", 2);
  cv::imwrite((dir / "depth" / "100.005000.png").string(), cv::Mat(24, 32, CV_16UC1, cv::Scalar(5000)));
  const io::TumSequence sequence = io::TumSequence::open(dir.string());
  PinholeCamera camera = smallCamera();
  camera.unregistered_depth = DepthCamera{30.0, 30.0, 15.5, 11.5, {0.025, 0.0, 0.0}, {}, 32, 24};
  const RgbdFrame frame = sequence.loadFrame(0, camera);
  EXPECT_EQ(frame.color.size(), cv::Size(64, 48));
  ASSERT_EQ(frame.depth.size(), cv::Size(32, 24));
  EXPECT_FLOAT_EQ(frame.depth.at<float>(10, 10), 5000.0f / static_cast<float>(camera.depth_factor));
  const std::string error = errorOf([&] { sequence.loadFrame(1, camera); });  // 64x48 depth
  EXPECT_NE(error.find(sequence.frame(1).depth_path), std::string::npos) << error;
  EXPECT_NE(error.find("64x48"), std::string::npos) << error;
  EXPECT_NE(error.find("depth camera's images are 32x24"), std::string::npos) << error;
}

TEST(TumSequence, ListsThatNeverMatchAreRefused) {
  const fs::path dir = writeSequence("tum_no_pairs", 2);
  writeFile(dir / "depth.txt", "500.0 depth/100.005000.png\n");
  const std::string error = errorOf([&] { io::TumSequence::open(dir.string()); });
  EXPECT_NE(error.find(dir.string()), std::string::npos) << error;
}

TEST(TumSequence, MalformedGroundTruthIsNamedWithItsLine) {
  const fs::path dir = writeSequence("tum_bad_groundtruth", 2);
  writeFile(dir / "groundtruth.txt", "# ground truth\n100.0 0 0 0 0 0 0 1\n100.01 0 0 0 0 0 0\n");
  const std::string error = errorOf([&] { io::TumSequence::open(dir.string()); });
  EXPECT_NE(error.find((dir / "groundtruth.txt").string() + ":3:"), std::string::npos) << error;
}
