#include <cmath>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "test_support.h"
#include "weighted_icp/io/camera.h"

using namespace weighted_icp;
namespace fs = std::filesystem;
using weighted_icp::testing::writeFile;

namespace {

std::string errorOf(const std::string& preset_or_path) {
  try {
    io::loadCamera(preset_or_path);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return {};
}


const char* const kCompleteYaml =
    "%YAML:1.0\n"
    "fx: 500.5\nfy: 501.25\ncx: 320.0\ncy: 240.0\n"
    "k1: 0.1\nk2: -0.2\np1: 0.001\np2: -0.002\nk3: 0.3\n"
    "width: 640\nheight: 480\ndepth_factor: 1000.0\n";

}  // namespace

TEST(Camera, TumPresetsHaveThePublishedCalibration) {
  // The values of the TUM RGB-D benchmark's published calibration table.
  const io::PinholeCamera fr1 = io::tumCamera(1);
  EXPECT_DOUBLE_EQ(fr1.fx, 517.306408);
  EXPECT_DOUBLE_EQ(fr1.fy, 516.469215);
  EXPECT_DOUBLE_EQ(fr1.cx, 318.643040);
  EXPECT_DOUBLE_EQ(fr1.cy, 255.313989);
  EXPECT_DOUBLE_EQ(fr1.distortion[0], 0.262383);
  EXPECT_DOUBLE_EQ(fr1.distortion[1], -0.953104);
  EXPECT_DOUBLE_EQ(fr1.distortion[2], -0.005358);
  EXPECT_DOUBLE_EQ(fr1.distortion[3], 0.002628);
  EXPECT_DOUBLE_EQ(fr1.distortion[4], 1.163314);
  EXPECT_TRUE(fr1.hasDistortion());

  const io::PinholeCamera fr2 = io::tumCamera(2);
  EXPECT_DOUBLE_EQ(fr2.fx, 520.908620);
  EXPECT_DOUBLE_EQ(fr2.fy, 521.007327);
  EXPECT_DOUBLE_EQ(fr2.cx, 325.141442);
  EXPECT_DOUBLE_EQ(fr2.cy, 249.701764);
  EXPECT_DOUBLE_EQ(fr2.distortion[0], 0.231222);
  EXPECT_DOUBLE_EQ(fr2.distortion[3], -0.000105);
  EXPECT_DOUBLE_EQ(fr2.distortion[4], 0.917205);

  const io::PinholeCamera fr3 = io::tumCamera(3);
  EXPECT_DOUBLE_EQ(fr3.fx, 535.4);
  EXPECT_DOUBLE_EQ(fr3.fy, 539.2);
  EXPECT_DOUBLE_EQ(fr3.cx, 320.1);
  EXPECT_DOUBLE_EQ(fr3.cy, 247.6);
  EXPECT_FALSE(fr3.hasDistortion());

  for (const auto& camera : {fr1, fr2, fr3}) {
    EXPECT_EQ(camera.width, 640);
    EXPECT_EQ(camera.height, 480);
    EXPECT_DOUBLE_EQ(camera.depth_factor, 5000.0);
  }
  EXPECT_THROW(io::tumCamera(4), std::invalid_argument);
  EXPECT_THROW(io::tumCamera(0), std::invalid_argument);
}

TEST(Camera, PresetNamesLoadThePresets) {
  for (int freiburg = 1; freiburg <= 3; ++freiburg) {
    const io::PinholeCamera preset = io::tumCamera(freiburg);
    const io::PinholeCamera loaded = io::loadCamera("fr" + std::to_string(freiburg));
    EXPECT_EQ(loaded.fx, preset.fx);
    EXPECT_EQ(loaded.cy, preset.cy);
    EXPECT_EQ(loaded.distortion, preset.distortion);
  }
}

TEST(Camera, MatricesHoldTheIntrinsics) {
  const io::PinholeCamera camera = io::tumCamera(1);
  const cv::Matx33d k = camera.cameraMatrix();
  EXPECT_EQ(k(0, 0), camera.fx);
  EXPECT_EQ(k(1, 1), camera.fy);
  EXPECT_EQ(k(0, 2), camera.cx);
  EXPECT_EQ(k(1, 2), camera.cy);
  EXPECT_EQ(k(2, 2), 1.0);
  EXPECT_EQ(k(0, 1), 0.0);
  EXPECT_EQ(k(1, 0), 0.0);
  const cv::Mat d = camera.distortionCoefficients();
  ASSERT_EQ(d.type(), CV_64F);
  ASSERT_EQ(d.rows, 1);
  ASSERT_EQ(d.cols, 5);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(d.at<double>(i), camera.distortion[static_cast<std::size_t>(i)]);
}

TEST(Camera, ProjectAndBackProjectAreInverse) {
  const io::PinholeCamera camera = io::tumCamera(1);
  for (const Eigen::Vector3d& point : {Eigen::Vector3d(0.3, -0.2, 1.5), Eigen::Vector3d(-1.0, 0.7, 4.0),
                                      Eigen::Vector3d(0.0, 0.0, 0.6)}) {
    const Eigen::Vector2d pixel = camera.project(point);
    EXPECT_TRUE(camera.backProject(pixel.x(), pixel.y(), point.z()).isApprox(point, 1e-12));
  }
  for (const Eigen::Vector3d& pixel_depth : {Eigen::Vector3d(10.0, 20.0, 1.0), Eigen::Vector3d(600.5, 470.25, 2.5)}) {
    const Eigen::Vector3d point = camera.backProject(pixel_depth.x(), pixel_depth.y(), pixel_depth.z());
    EXPECT_DOUBLE_EQ(point.z(), pixel_depth.z());
    EXPECT_TRUE(camera.project(point).isApprox(pixel_depth.head<2>(), 1e-12));
  }
  // The principal point is where the optical axis meets the image.
  EXPECT_TRUE(camera.project(Eigen::Vector3d(0.0, 0.0, 2.0)).isApprox(Eigen::Vector2d(camera.cx, camera.cy)));
}

TEST(Camera, PointsBehindTheCameraAreNotInTheImage) {
  const io::PinholeCamera camera = io::tumCamera(3);
  EXPECT_FALSE(camera.inImage(camera.project(Eigen::Vector3d(0.0, 0.0, -1.0))));
  EXPECT_FALSE(camera.inImage(camera.project(Eigen::Vector3d(0.1, 0.1, 0.0))));
}

TEST(Camera, InImageCoversExactlyThePixelCentres) {
  const io::PinholeCamera camera = io::tumCamera(3);
  EXPECT_TRUE(camera.inImage({0.0, 0.0}));
  EXPECT_TRUE(camera.inImage({camera.width - 1.0, camera.height - 1.0}));
  EXPECT_FALSE(camera.inImage({-0.01, 10.0}));
  EXPECT_FALSE(camera.inImage({10.0, -0.01}));
  EXPECT_FALSE(camera.inImage({camera.width - 0.99, 10.0}));
  EXPECT_FALSE(camera.inImage({10.0, camera.height - 0.99}));
  EXPECT_FALSE(camera.inImage({std::numeric_limits<double>::quiet_NaN(), 10.0}));
}

TEST(Camera, YamlRoundTripKeepsEveryValue) {
  const auto dir = weighted_icp::testing::scratchDir("camera_round_trip");
  io::PinholeCamera camera = io::tumCamera(1);
  camera.fx = 1.0 / 3.0 + 500.0;  // not exactly representable in decimal
  camera.width = 1280;
  camera.height = 720;
  camera.depth_factor = 1000.0;
  const std::string path = (dir / "camera.yaml").string();
  io::saveCamera(camera, path);
  const io::PinholeCamera loaded = io::loadCamera(path);
  EXPECT_EQ(loaded.fx, camera.fx);
  EXPECT_EQ(loaded.fy, camera.fy);
  EXPECT_EQ(loaded.cx, camera.cx);
  EXPECT_EQ(loaded.cy, camera.cy);
  EXPECT_EQ(loaded.distortion, camera.distortion);
  EXPECT_EQ(loaded.width, camera.width);
  EXPECT_EQ(loaded.height, camera.height);
  EXPECT_EQ(loaded.depth_factor, camera.depth_factor);
  // Atomic write: nothing but the camera file is left in the folder.
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
}

TEST(Camera, HandWrittenYamlLoads) {
  const auto dir = weighted_icp::testing::scratchDir("camera_hand_written");
  writeFile(dir / "camera.yaml", kCompleteYaml);
  const io::PinholeCamera camera = io::loadCamera((dir / "camera.yaml").string());
  EXPECT_EQ(camera.fx, 500.5);
  EXPECT_EQ(camera.fy, 501.25);
  EXPECT_EQ(camera.distortion[1], -0.2);
  EXPECT_EQ(camera.distortion[4], 0.3);
  EXPECT_EQ(camera.depth_factor, 1000.0);
}

TEST(Camera, EveryMissingKeyIsNamedAtOnce) {
  const auto dir = weighted_icp::testing::scratchDir("camera_missing_keys");
  const fs::path path = dir / "partial.yaml";
  writeFile(path, "%YAML:1.0\nfx: 500.0\ncx: 320.0\ncy: 240.0\nk1: 0\nk2: 0\np1: 0\np2: 0\nwidth: 640\nheight: 480\n");
  const std::string error = errorOf(path.string());
  EXPECT_NE(error.find(path.string()), std::string::npos) << error;
  for (const char* key : {"fy", "k3", "depth_factor"})
    EXPECT_NE(error.find(std::string(key) + " is missing"), std::string::npos) << key << ": " << error;
  for (const char* key : {"fx ", "cx ", "width "}) EXPECT_EQ(error.find(key), std::string::npos) << error;
}

TEST(Camera, InvalidValuesAreRefusedWithTheirKeys) {
  const auto dir = weighted_icp::testing::scratchDir("camera_invalid");
  const fs::path path = dir / "invalid.yaml";
  writeFile(path,
            "%YAML:1.0\nfx: -500.0\nfy: 0\ncx: .nan\ncy: 240.0\nk1: 0\nk2: 0\np1: 0\np2: 0\nk3: 0\n"
            "width: 640.5\nheight: -480\ndepth_factor: \"many\"\n");
  const std::string error = errorOf(path.string());
  EXPECT_NE(error.find(path.string()), std::string::npos) << error;
  for (const char* key : {"fx", "fy", "cx", "width", "height", "depth_factor"})
    EXPECT_NE(error.find(std::string(key) + " "), std::string::npos) << key << ": " << error;
  EXPECT_EQ(error.find("cy "), std::string::npos) << error;
}

TEST(Camera, UnreadableFilesAreNamed) {
  const auto dir = weighted_icp::testing::scratchDir("camera_unreadable");
  const std::string missing = (dir / "absent.yaml").string();
  EXPECT_NE(errorOf(missing).find(missing), std::string::npos);
  EXPECT_NE(errorOf("fr4").find("fr4"), std::string::npos);
  const fs::path garbage = dir / "garbage.yaml";
  writeFile(garbage, "%YAML:1.0\nfx: [1, 2\n  : : }\n");
  EXPECT_NE(errorOf(garbage.string()).find(garbage.string()), std::string::npos);
  const fs::path list = dir / "list.yaml";  // valid YAML, but no keys
  writeFile(list, "%YAML:1.0\n- 1\n- 2\n");
  EXPECT_NE(errorOf(list.string()).find(list.string()), std::string::npos);
  const fs::path empty = dir / "empty.yaml";
  writeFile(empty, "");
  EXPECT_NE(errorOf(empty.string()).find(empty.string()), std::string::npos);
}

TEST(Camera, InvalidCamerasAreNotSaved) {
  const auto dir = weighted_icp::testing::scratchDir("camera_save_invalid");
  io::PinholeCamera camera = io::tumCamera(3);
  camera.depth_factor = 0.0;
  const std::string path = (dir / "camera.yaml").string();
  EXPECT_THROW(io::saveCamera(camera, path), std::runtime_error);
  EXPECT_FALSE(fs::exists(path));
  camera = io::tumCamera(3);
  camera.fy = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(io::saveCamera(camera, path), std::runtime_error);
  EXPECT_FALSE(fs::exists(path));
}
